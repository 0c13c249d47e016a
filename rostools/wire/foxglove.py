"""The Foxglove WebSocket protocol (``foxglove.websocket.v1``) over bytes and JSON, sans IO.

What the bridge sends and what it accepts from a client, checked before anything acts on it:
every client message either reads as one of the protocol's operations, with fields of the
right types, or raises ``ProtocolError`` naming what is wrong, which the bridge answers with a
``status`` message. The layout of the binary messages is the protocol's (little-endian,
opcode first), as github.com/foxglove/ws-protocol specifies it.
"""

from __future__ import annotations

import json
import struct
from typing import Any, NamedTuple

#: The subprotocol names we accept, newest first: Foxglove's SDK renamed it, and older
#: Studio, Lichtblick and PlotJuggler offer only the first name they knew.
SUBPROTOCOLS = ("foxglove.sdk.v1", "foxglove.websocket.v1")

# server binary opcodes
MESSAGE_DATA, TIME, SERVICE_CALL_RESPONSE = 1, 2, 3
# client binary opcodes
CLIENT_MESSAGE_DATA, SERVICE_CALL_REQUEST = 1, 2
# status levels
INFO, WARNING, ERROR = 0, 1, 2

#: Capabilities this server may announce.
CLIENT_PUBLISH = "clientPublish"
PARAMETERS = "parameters"
PARAMETERS_SUBSCRIBE = "parametersSubscribe"
CAPABILITY_TIME = "time"
SERVICES = "services"
CONNECTION_GRAPH = "connectionGraph"

#: Ids are unsigned 32-bit in the binary messages.
MAX_ID = 2**32 - 1

_MESSAGE = struct.Struct("<BIQ")
_TIME = struct.Struct("<BQ")
_U32 = struct.Struct("<I")
_CALL = struct.Struct("<BIII")


class ProtocolError(ValueError):
    """A client message that is not the protocol; the text says what is wrong, in words."""


def message_data(subscription: int, timestamp_ns: int) -> bytes:
    """The 13 bytes that go before a message's payload."""
    return _MESSAGE.pack(MESSAGE_DATA, subscription, timestamp_ns)


def time_message(timestamp_ns: int) -> bytes:
    """The server's clock, for clients of a graph on sim time."""
    return _TIME.pack(TIME, timestamp_ns)


def service_response(service: int, call: int, encoding: str, payload: bytes) -> bytes:
    """A service call's response."""
    name = encoding.encode()
    return _CALL.pack(SERVICE_CALL_RESPONSE, service, call, len(name)) + name + payload


def dumps(message: dict[str, Any]) -> str:
    """A JSON message, compact; NaN is not JSON, so a value carrying it is refused here."""
    return json.dumps(message, separators=(",", ":"), allow_nan=False)


class ClientData(NamedTuple):
    """A message a client publishes on a channel it advertised."""

    channel: int
    payload: memoryview


class CallRequest(NamedTuple):
    """A client's service call."""

    service: int
    call: int
    encoding: str
    payload: memoryview


def parse_binary(data: bytes) -> ClientData | CallRequest:
    """A client's binary message."""
    view = memoryview(data)
    if not view:
        raise ProtocolError("an empty binary message")
    op = view[0]
    if op == CLIENT_MESSAGE_DATA:
        if len(view) < 5:
            raise ProtocolError("a message data frame shorter than its 5-byte header")
        return ClientData(_U32.unpack_from(view, 1)[0], view[5:])
    if op == SERVICE_CALL_REQUEST:
        if len(view) < _CALL.size:
            raise ProtocolError("a service call request shorter than its 13-byte header")
        _, service, call, length = _CALL.unpack_from(view)
        end = _CALL.size + length
        if end > len(view):
            raise ProtocolError(f"a service call's encoding of {length} bytes runs past the end")
        try:
            encoding = bytes(view[_CALL.size : end]).decode()
        except UnicodeDecodeError:
            raise ProtocolError("a service call's encoding is not UTF-8") from None
        return CallRequest(service, call, encoding, view[end:])
    raise ProtocolError(f"unknown binary opcode {op}")


#: What each client operation must carry: field -> the JSON types it may have.
_LIST, _STR, _INT, _OBJ = (list,), (str,), (int,), (dict,)
OPERATIONS: dict[str, dict[str, tuple[type, ...]]] = {
    "subscribe": {"subscriptions": _LIST},
    "unsubscribe": {"subscriptionIds": _LIST},
    "advertise": {"channels": _LIST},
    "unadvertise": {"channelIds": _LIST},
    "getParameters": {"parameterNames": _LIST},
    "setParameters": {"parameters": _LIST},
    "subscribeParameterUpdates": {"parameterNames": _LIST},
    "unsubscribeParameterUpdates": {"parameterNames": _LIST},
    "subscribeConnectionGraph": {},
    "unsubscribeConnectionGraph": {},
    "fetchAsset": {"uri": _STR, "requestId": _INT},
}


def parse_json(text: str) -> dict[str, Any]:
    """A client's JSON message: an object with a known ``op`` and its fields."""
    try:
        message = json.loads(text)
    except (ValueError, RecursionError) as err:
        raise ProtocolError(f"not JSON: {err}") from None
    if not isinstance(message, dict):
        raise ProtocolError("a message that is not a JSON object")
    op = message.get("op")
    fields = OPERATIONS.get(op) if isinstance(op, str) else None
    if fields is None:
        raise ProtocolError(f"unknown op {op!r}")
    for name, types in fields.items():
        if not isinstance(message.get(name), types) or isinstance(message.get(name), bool):
            raise ProtocolError(f"{op}: {name} missing or not a {types[0].__name__}")
    return message


def field(item: Any, name: str, kind: type, op: str) -> Any:
    """``item[name]``, checked to be a ``kind`` (an id: an unsigned 32-bit integer)."""
    value: Any = item.get(name) if isinstance(item, dict) else None
    ok = isinstance(value, kind) and not isinstance(value, bool)
    if ok and kind is int and not 0 <= value <= MAX_ID:
        ok = False
    if not ok:
        raise ProtocolError(f"{op}: {name} missing or not a{'n id' if kind is int else ' string'}")
    return value


def ids(values: list[Any], op: str) -> list[int]:
    """A list of ids, each checked."""
    return [field({"id": v}, "id", int, op) for v in values]
