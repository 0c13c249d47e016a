"""What the master knows about topics, for the topic commands (blocking calls)."""

from __future__ import annotations

from rostools.errors import RostoolsError
from rostools.names import ANYTYPE, make_global_ns
from rostools.rosgraph.views import Record

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from collections.abc import Iterator
    from typing import Any

    from rostools.msgs.store import TypeStore
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


class TopicRef(Record):
    """A topic as the user named it: the real topic, its type, and a field path after it."""

    __slots__ = ("field", "topic", "type")

    def __init__(self, topic: str, type: str | None, field: str) -> None:
        self.topic = topic
        self.type = type
        self.field = field


def _prefixes(
    name: str, types: dict[str, str], store: TypeStore | None
) -> Iterator[tuple[str, str, str, str | None]]:
    """The advertised topics that ``name`` extends, longest first.

    Each as (topic, type, the field path after it, why that path is not a field of the type):
    the last is None when it is one, or when the type is unknown here.
    """
    name = name.rstrip("/") or "/"
    for topic in sorted((t for t in types if name.startswith(t + "/")), key=len, reverse=True):
        kind, path = types[topic], name[len(topic) + 1 :]
        error = None
        if store is not None and kind != ANYTYPE and store.has_msg(kind):
            from rostools.msgs import fieldpath  # only when a path has to be checked

            try:
                fieldpath.resolve(store, kind, path)
            except RostoolsError as err:
                error = str(err)
        yield topic, kind, path, error


def field_problem(name: str, types: dict[str, str], store: TypeStore) -> str | None:
    """Why ``/topic/field/path`` matched no topic when a prefix of it is one: its field error."""
    for topic, kind, _, error in _prefixes(name, types, store):
        if error is not None:
            return f"{topic} is {kind}: {error}"
    return None


def split_field(name: str, types: dict[str, str], store: TypeStore | None) -> TopicRef | None:
    """Find the topic in ``/topic/field/path`` as rostopic does.

    An exact match first, else the longest advertised prefix whose type has the field (types
    unknown here are accepted).
    """
    exact = name.rstrip("/") or "/"
    if exact in types:
        kind = types[exact]
        return TopicRef(exact, None if kind == ANYTYPE else kind, "")
    for topic, kind, path, error in _prefixes(name, types, store):
        if error is None:
            return TopicRef(topic, None if kind == ANYTYPE else kind, path)
    return None
