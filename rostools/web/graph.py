"""The graph as the bridge shows it: topics with publishers, services, who offers what.

ROS 1's master tells nobody when a topic appears; a bridge must ask. ``GraphWatch`` asks for
the whole graph in one ``system.multicall`` (``getSystemState`` and ``getTopicTypes``) every
``PERIOD``, so a new topic reaches clients within a second (foxglove_bridge for ROS 1 asks
every 5 s), and hands each change to the bridge as one ``GraphChange``.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from typing import Any

from rostools.node.mastercalls import LiveMaster
from rostools.rosgraph.masterapi import master_timeout

log = logging.getLogger(__name__)

#: Seconds between two looks at the graph: new topics reach clients within this and a call.
PERIOD = 0.5


def _names(entries: Any) -> dict[str, list[str]]:
    """``[[name, [node, ...]], ...]`` as a dict, a peer's junk left out."""
    out: dict[str, list[str]] = {}
    for entry in entries if isinstance(entries, list) else []:
        if isinstance(entry, list) and len(entry) == 2 and isinstance(entry[0], str):
            nodes = entry[1] if isinstance(entry[1], list) else []
            out[entry[0]] = sorted(str(n) for n in nodes)
    return out


@dataclass
class Graph:
    """One look at the graph."""

    #: topic -> type, for topics with at least one publisher
    topics: dict[str, str] = field(default_factory=dict)
    publishers: dict[str, list[str]] = field(default_factory=dict)
    subscribers: dict[str, list[str]] = field(default_factory=dict)
    #: service -> the nodes that offer it
    services: dict[str, list[str]] = field(default_factory=dict)

    @classmethod
    def of(cls, state: Any, types: Any) -> Graph:
        """From ``getSystemState`` and ``getTopicTypes`` values."""
        pubs, subs, srvs = state if isinstance(state, list) and len(state) == 3 else ([], [], [])
        known = {
            str(t[0]): str(t[1])
            for t in (types if isinstance(types, list) else [])
            if isinstance(t, list) and len(t) == 2
        }
        publishers = {t: n for t, n in _names(pubs).items() if n}
        topics = {t: known.get(t, "") for t in publishers}
        return cls(topics, publishers, _names(subs), _names(srvs))


@dataclass
class GraphChange:
    """What changed between two looks."""

    new: Graph
    added_topics: dict[str, str]
    removed_topics: list[str]
    added_services: list[str]
    removed_services: list[str]
    #: whether who publishes, subscribes or serves what changed (the connection graph)
    links_changed: bool


def diff(old: Graph, new: Graph) -> GraphChange:
    """The change from ``old`` to ``new``; a topic whose type changed is removed and added."""
    added = {t: ty for t, ty in new.topics.items() if old.topics.get(t) != ty}
    removed = [t for t, ty in old.topics.items() if new.topics.get(t) != ty]
    links = (old.publishers, old.subscribers, old.services) != (
        new.publishers,
        new.subscribers,
        new.services,
    )
    return GraphChange(
        new,
        added,
        removed,
        [s for s in new.services if s not in old.services],
        [s for s in old.services if s not in new.services],
        links,
    )


class GraphWatch:
    """Looks at the graph every ``PERIOD`` and reports each change."""

    def __init__(
        self, master: LiveMaster, on_change: Callable[[GraphChange], Awaitable[None]]
    ) -> None:
        self.master = master
        self.on_change = on_change
        self.graph = Graph()
        #: Set once the first look is done (the first change has been handed over).
        self.ready = asyncio.Event()
        self._lost = False

    async def look(self) -> None:
        """One look, and the change handed over."""
        state, types = await self.master.multicall(
            [("getSystemState", ()), ("getTopicTypes", ())], timeout=master_timeout()
        )
        for value in (state, types):
            if isinstance(value, BaseException):
                raise value
        new = Graph.of(state, types)
        change = diff(self.graph, new)
        self.graph = new
        await self.on_change(change)
        self.ready.set()

    async def run(self, period: float = PERIOD) -> None:
        """Look until cancelled; a master that does not answer is tried again."""
        while True:
            try:
                await self.look()
                self._lost = False
            except Exception as err:  # noqa: BLE001 - the master may come back
                if not self._lost:
                    log.warning("the bridge cannot read the graph: %s", err)
                self._lost = True
            await asyncio.sleep(period)
