"""Which topics a live command follows: rosbag record's names, regexes, types and excludes.

``bag record``, ``bag snapshot`` and ``bridge`` choose their topics alike; ``Selection`` is the
one reading of that choice.
"""

from __future__ import annotations

import fnmatch
import re
from dataclasses import dataclass, field

from rostools.errors import UsageError


@dataclass
class TopicChoice:
    """Which topics to follow: rosbag record's ``TOPICS``, ``-a``, ``-e``, ``-x``, ``--node``."""

    topics: list[str] = field(default_factory=list)
    all: bool = False
    regex: bool = False
    exclude: list[str] = field(default_factory=list)  # regexes; a topic matching any is left out
    types: list[str] = field(default_factory=list)  # globs: topics of these types too
    exclude_types: list[str] = field(default_factory=list)  # globs: never these types
    node: str | None = None


class Selection:
    """Which topics to record: names, regexes (full match, as rosbag), types, all, minus excludes.

    Types are globs (``sensor_msgs/*``), as rosbag2's ``--topic-types``; a topic whose type is
    not known yet waits for the next poll when types decide.
    """

    def __init__(self, opts: TopicChoice) -> None:
        self.types = opts.types
        self.exclude_types = opts.exclude_types
        self.names = set(opts.topics) if not opts.regex else set()
        try:
            self.patterns = [re.compile(p) for p in opts.topics] if opts.regex else []
            self.exclude = [re.compile(x) for x in opts.exclude]
        except re.error as err:
            raise UsageError(f"bad regular expression: {err}") from err
        # --node records what the node subscribes to; -x alone means everything but that
        self.everything = (
            opts.all or opts.node is not None or (bool(opts.exclude) and not opts.topics)
        )

    @property
    def by_type(self) -> bool:
        """Whether topic types take part in the choice."""
        return bool(self.types or self.exclude_types)

    def wants(self, topic: str, topic_type: str | None = None) -> bool:
        """Whether to record ``topic`` (of ``topic_type``, if known)."""
        if any(x.fullmatch(topic) for x in self.exclude):
            return False
        if self.exclude_types and (topic_type is None or _matches(topic_type, self.exclude_types)):
            return False
        if self.everything or topic in self.names or any(p.fullmatch(topic) for p in self.patterns):
            return True
        return topic_type is not None and _matches(topic_type, self.types)


def _matches(topic_type: str, globs: list[str]) -> bool:
    return any(fnmatch.fnmatchcase(topic_type, g) for g in globs)
