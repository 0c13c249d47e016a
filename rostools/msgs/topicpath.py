"""``/topic/field/path``: which topic a name means, and the field path after it.

``rostopic echo /odom/pose/pose`` names a topic and a field of its messages in one name; so
do echo, ``topic type``, ``topic plot``, ``bag plot`` and ``topic echo -b``, and all of them
split it here. The field path itself is ``fieldpath``'s, imported only when a path has to be
checked against a type: ``topic type /chatter`` runs on the quick path, which imports neither
``typing`` nor ``dataclasses``.
"""

from __future__ import annotations

from rostools.errors import RostoolsError
from rostools.names import ANYTYPE

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from collections.abc import Iterator

    from rostools.msgs.store import TypeStore


class TopicRef:
    """A topic as the user named it: the real topic, its type, and a field path after it."""

    __slots__ = ("field", "topic", "type")

    def __init__(self, topic: str, type: str | None, field: str) -> None:
        self.topic = topic
        self.type = type
        self.field = field

    def __repr__(self) -> str:
        return f"TopicRef({self.topic!r}, {self.type!r}, {self.field!r})"


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
