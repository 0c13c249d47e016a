"""The rosbridge v2 protocol's messages, sans-IO.

What a client sends, checked, and what the bridge sends back (``status``, ``fragment``,
``publish``), as rosbridge_server 0.11.17 and the protocol's specification (in
rosbridge_suite) have them.

A client's message is one JSON object with an ``op``; anything else is a ``ProtocolError``
whose text a ``status`` message carries back. ``Fragments`` puts a client's fragmented
message together again, within bounds.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any

#: The status levels, least severe first; a client hears a status at its level or above.
LEVELS = ("info", "warning", "error", "none")
#: The level a client starts at (the specification's section 3.2).
DEFAULT_LEVEL = "error"
#: Compressions a subscription may ask for; the strongest among a client's subscriptions to
#: one topic wins, as in rosbridge.
COMPRESSIONS = ("none", "png", "cbor", "cbor-raw")
#: A client's fragmented messages being put together at once, and the bytes of each.
MAX_FRAGMENT_SETS = 16
MAX_FRAGMENTED_BYTES = 16 * 1024 * 1024


class ProtocolError(ValueError):
    """A client's message the bridge cannot act on; its text is the status sent back."""

    def __init__(self, text: str, ident: Any = None, level: str = "error") -> None:
        super().__init__(text)
        self.ident = ident
        self.level = level


def parse(text: str) -> dict[str, Any]:
    """A client's message as a JSON object with a string ``op``."""
    try:
        message = json.loads(text)
    except ValueError as err:
        raise ProtocolError(f"not a JSON message ({err})") from None
    if not isinstance(message, dict):
        raise ProtocolError(f"a message must be a JSON object, not {type(message).__name__}")
    ident = message.get("id")
    if isinstance(ident, dict | list):  # it keys a client's subscriptions and fragments
        raise ProtocolError(f"id must be a string or a number, not {json.dumps(ident)[:40]}")
    op = message.get("op")
    if op is None:
        raise ProtocolError("a message without an op: every message needs one", ident)
    if not isinstance(op, str):
        raise ProtocolError(f"op must be a string, not {json.dumps(op)[:40]}", ident)
    return message


#: JSON's kinds, as a check names them.
_KINDS: dict[type, str] = {str: "a string", int: "an integer", bool: "true or false",
                           dict: "an object", list: "an array"}  # fmt: skip


def need(message: dict[str, Any], name: str, kind: type, required: bool = True) -> Any:
    """The field ``name`` of ``message``, of JSON kind ``kind`` (None if optional and absent)."""
    op = message["op"]
    if name not in message or (message[name] is None and not required):
        if required:
            raise ProtocolError(
                f"{op}: expected a {name} field but none was found", message.get("id")
            )
        return None
    value = message[name]
    ok = isinstance(value, kind) and not (kind is int and isinstance(value, bool))
    if not ok:
        raise ProtocolError(
            f"{op}: {name} must be {_KINDS.get(kind, kind.__name__)}, not {json.dumps(value)[:60]}",
            message.get("id"),
        )
    return value


def status(level: str, text: str, ident: Any = None) -> dict[str, Any]:
    """A ``status`` message."""
    message: dict[str, Any] = {"op": "status"}
    if ident is not None:
        message["id"] = ident
    message["level"] = level
    message["msg"] = text
    return message


def heard(level: str, client_level: str) -> bool:
    """Whether a client at ``client_level`` hears a status of ``level``."""
    return client_level != "none" and LEVELS.index(level) >= LEVELS.index(client_level)


def fragments(text: str, size: int, ident: Any) -> list[str]:
    """``text`` cut into ``fragment`` messages of ``size`` characters of data each."""
    total = (len(text) + size - 1) // size
    parts = [text[i * size : (i + 1) * size] for i in range(total)]
    return [
        _COMPACT({"op": "fragment", "id": ident, "data": part, "num": i, "total": total})
        for i, part in enumerate(parts)
    ]


_COMPACT = json.JSONEncoder(separators=(",", ":")).encode


def publish_json(topic: str, msg: str) -> str:
    """A ``publish`` message around a message already in JSON."""
    return '{"op":"publish","topic":' + json.dumps(topic) + ',"msg":' + msg + "}"


@dataclass
class _Partial:
    total: int
    parts: dict[int, str] = field(default_factory=dict)
    size: int = 0


class Fragments:
    """A client's fragmented messages, put together again (``fragment`` ops)."""

    def __init__(self) -> None:
        self._sets: dict[str, _Partial] = {}

    def add(self, message: dict[str, Any]) -> str | None:
        """Take one ``fragment``; the whole message's text once its last part is in."""
        ident = message.get("id")
        data = need(message, "data", str)
        num = need(message, "num", int)
        total = need(message, "total", int)
        key = json.dumps(ident)
        if not 0 <= num < total:
            raise ProtocolError(f"fragment: num {num} is not within total {total}", ident)
        partial = self._sets.get(key)
        if partial is None:
            if len(self._sets) >= MAX_FRAGMENT_SETS:
                raise ProtocolError(
                    f"fragment: more than {MAX_FRAGMENT_SETS} fragmented messages at once", ident
                )
            partial = self._sets[key] = _Partial(total)
        if partial.total != total:
            del self._sets[key]
            raise ProtocolError(f"fragment: total {total} changed from {partial.total}", ident)
        partial.size += len(data) - len(partial.parts.get(num, ""))
        partial.parts[num] = data
        if partial.size > MAX_FRAGMENTED_BYTES:
            del self._sets[key]
            raise ProtocolError(
                f"fragment: the message is over {MAX_FRAGMENTED_BYTES >> 20} MiB: dropped", ident
            )
        if len(partial.parts) < total:
            return None
        del self._sets[key]
        return "".join(partial.parts[i] for i in range(total))
