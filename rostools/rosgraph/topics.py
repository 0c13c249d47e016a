"""What the master knows about topics, for the topic commands (blocking calls)."""

from __future__ import annotations

from rostools.names import make_global_ns
from rostools.rosgraph.views import Record

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from typing import Any

    from rostools.rosgraph.masterapi import MasterProxy


class TopicInfo(Record):
    """A topic: its type and the nodes on each end."""

    __slots__ = ("name", "publishers", "subscribers", "type")

    def __init__(
        self,
        name: str,
        type: str,
        publishers: list[str] | None = None,
        subscribers: list[str] | None = None,
    ) -> None:
        self.name = name
        self.type = type
        self.publishers: list[str] = [] if publishers is None else publishers
        self.subscribers: list[str] = [] if subscribers is None else subscribers

    def as_dict(self) -> dict[str, Any]:
        """As plain data."""
        return {
            "topic": self.name,
            "type": self.type,
            "publishers": self.publishers,
            "subscribers": self.subscribers,
        }


def topic_table(master: MasterProxy, namespace: str | None = None) -> dict[str, TopicInfo]:
    """Every topic with a publisher or subscriber, optionally under ``namespace``."""
    pubs, subs, _ = master.system_state()
    types = master.topic_types()
    table: dict[str, TopicInfo] = {}
    for rows, attr in ((pubs, "publishers"), (subs, "subscribers")):
        for topic, nodes in rows:
            info = table.setdefault(topic, TopicInfo(topic, types.get(topic, "unknown type")))
            getattr(info, attr).extend(nodes)
    if namespace and namespace != "/":
        prefix = make_global_ns(namespace)
        table = {t: i for t, i in table.items() if t == namespace or t.startswith(prefix)}
    return dict(sorted(table.items()))


def host_of(uri: str) -> str:
    """The host part of a node's XML-RPC URI."""
    from urllib.parse import urlsplit

    return urlsplit(uri).hostname or "unknown"
