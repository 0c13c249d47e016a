"""What a topic carries (type name, md5sum, full definition), and what a service does."""

from __future__ import annotations

from typing import NamedTuple

from rostools.msgs.store import TypeStore


class TopicType(NamedTuple):
    """The type of a topic as TCPROS headers carry it."""

    type: str
    md5sum: str
    definition: str
    has_header: bool = False

    @classmethod
    def of(cls, store: TypeStore, name: str) -> TopicType:
        """The type ``name`` as the store knows it."""
        spec = store.msg(name)
        return cls(spec.name, store.md5(name), store.full_text(name), spec.has_header)

    @classmethod
    def from_header(cls, header: dict[str, str], store: TypeStore | None = None) -> TopicType:
        """The type a publisher announced in its connection header."""
        name = header.get("type", "*")
        definition = header.get("message_definition", "")
        has_header = False
        if store is not None and name != "*":
            try:
                has_header = store.with_definition(name, definition).msg(name).has_header
            except Exception:  # noqa: BLE001 - a broken definition only costs seq rewriting
                has_header = False
        return cls(name, header.get("md5sum", "*"), definition, has_header)


class ServiceType(NamedTuple):
    """A service type as TCPROS headers carry it."""

    type: str
    md5sum: str

    @classmethod
    def of(cls, store: TypeStore, name: str) -> ServiceType:
        """The service type ``name`` as the store knows it."""
        return cls(store.srv(name).name, store.srv_md5(name))


ANY = TopicType("*", "*", "")
