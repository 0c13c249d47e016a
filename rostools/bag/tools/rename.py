"""Renaming topics and types while a bag is copied (``--rename``, ``--rename-type``).

A topic rule ``/old:=/new`` is the remap syntax of ``bag play``. A type rule ``pkg/Old:=pkg/New``
renames the type of every connection that has it, and its ``MSG:`` section and field
references in every definition that embeds it. A message's md5sum does not cover its own type
name, nor the names of the types it embeds, so the bytes stay valid; the md5sum is checked
anyway, and a rule that would change it is refused.
"""

from __future__ import annotations

import dataclasses
import re
from collections.abc import Iterable, Mapping

from rostools.bag.formats.model import BagUsageError, Connection
from rostools.names import canonicalize, is_global, is_legal

_TYPE = re.compile(r"[A-Za-z][\w]*/[A-Za-z][\w]*")


def _rule(text: str, what: str, example: str) -> tuple[str, str]:
    old, sep, new = text.partition(":=")
    if not sep or not old or not new:
        raise BagUsageError(f"{what} {text!r}: give OLD:=NEW, e.g. {example}")
    return old, new


def _topic_rules(rules: Iterable[str]) -> dict[str, str]:
    found: dict[str, str] = {}
    for text in rules:
        old, new = (canonicalize(n) for n in _rule(text, "--rename", "/cam:=/camera"))
        for name in (old, new):
            if not (is_legal(name) and is_global(name)):
                raise BagUsageError(f"--rename {text!r}: {name!r} is not a global topic name")
        if found.setdefault(old, new) != new:
            raise BagUsageError(f"--rename: {old} is renamed twice")
    return found


def _type_rules(rules: Iterable[str]) -> dict[str, str]:
    found: dict[str, str] = {}
    for text in rules:
        old, new = _rule(text, "--rename-type", "old_msgs/Pose:=new_msgs/Pose")
        for name in (old, new):
            if not _TYPE.fullmatch(name):
                raise BagUsageError(f"--rename-type {text!r}: {name!r} is not a package/Type")
        if found.setdefault(old, new) != new:
            raise BagUsageError(f"--rename-type: {old} is renamed twice")
    return found


class Renames:
    """Topic and type renaming rules, applied to connections as they are copied."""

    def __init__(self, topics: Mapping[str, str], types: Mapping[str, str]) -> None:
        self.topics = dict(topics)
        self.types = dict(types)

    @classmethod
    def parse(cls, topic_rules: Iterable[str] = (), type_rules: Iterable[str] = ()) -> Renames:
        """Rules from ``/old:=/new`` and ``pkg/Old:=pkg/New`` texts; BagUsageError if bad."""
        return cls(_topic_rules(topic_rules), _type_rules(type_rules))

    def __bool__(self) -> bool:
        return bool(self.topics or self.types)

    def topic(self, name: str) -> str:
        """The name a topic is written under."""
        return self.topics.get(name, name)

    def connection(self, conn: Connection) -> Connection:
        """``conn`` as it is written: renamed, or itself when no rule applies."""
        topic = self.topic(conn.topic)
        extra = dict(conn.extra)
        if extra.get("topic") in self.topics:  # the header's own topic field, when it differs
            extra["topic"] = self.topics[extra["topic"]]
        kind, definition = conn.type, conn.definition
        if self.types:
            kind = self.types.get(kind, kind)
            definition = self._definition(definition)
            if (kind, definition) != (conn.type, conn.definition):
                self._check_md5(conn, kind, definition)
        if (topic, kind, definition, extra) == (conn.topic, conn.type, conn.definition, conn.extra):
            return conn
        return dataclasses.replace(conn, topic=topic, type=kind, definition=definition, extra=extra)

    def _definition(self, text: str) -> str:
        """Embedded types renamed: their ``MSG:`` lines and the fields that use them."""
        out = []
        for line in text.split("\n"):
            if line.startswith("MSG: "):
                name = line[5:].strip()
                line = f"MSG: {self.types.get(name, name)}"
            else:
                head, sep, rest = line.partition(" ")
                base, bracket, dims = head.partition("[")
                if sep and base in self.types:
                    line = f"{self.types[base]}{bracket}{dims}{sep}{rest}"
            out.append(line)
        return "\n".join(out)

    @staticmethod
    def _check_md5(conn: Connection, kind: str, definition: str) -> None:
        from rostools.msgs.store import md5_of

        if not md5_of(conn.type, conn.definition):
            return  # a definition that did not resolve before cannot be checked after
        got = md5_of(kind, definition)
        if not got:
            raise BagUsageError(
                f"renaming types on {conn.topic} leaves its {kind} definition unresolved "
                "(a field names the old type without its package?)"
            )
        if conn.md5sum not in ("*", got):
            raise BagUsageError(
                f"renaming {conn.type} on {conn.topic} to {kind} would change its md5sum "
                f"({conn.md5sum} -> {got}); a type can only be renamed where it stays the same"
            )
