"""The TCPROS frame limit, ``MAX_FRAME``: a frame of exactly the limit is taken, one byte over
is not.

roscpp drops a connection whose frame is over 1e9 bytes (``Connection::read``), so a frame
of exactly 1e9 is one it would read. Every place that reads a length prefix from a peer is
tested at the boundary: the subscriber's connection (``SubscriberStream``, ``InboundConnection``),
the connections a node's TCPROS server accepts (``ServerConnection``), and a service
client's replies (``ResponseReader``). A whole frame of 1e9 bytes is not sent: its prefix and
a first piece show whether it is taken, since a frame is refused as soon as its prefix is
read. Smaller limits check that frames of exactly the limit arrive byte for byte.
"""

from __future__ import annotations

import asyncio
import inspect
import struct
from typing import Any

import pytest

from rostools.node.connection import InboundConnection, ServerConnection
from rostools.node.subscriber import Subscriber
from rostools.wire.header import MAX_HEADER_LENGTH, encode_header
from rostools.wire.tcpros import (
    BIG_FRAME,
    MAX_FRAME,
    Accepted,
    Failed,
    FrameError,
    FrameReader,
    Messages,
    ResponseReader,
    SubscriberStream,
    publisher_header,
    service_reply_header,
)
from tests.support.fakeconn import FakeTransport, FrameHandler

_U32 = struct.Struct("<I")
REPLY = publisher_header("/talker", "/chatter", "m" * 32, "std_msgs/String", "string data", False)


def _feed(target: Any, data: bytes, out: list[Any] | None = None) -> list[Any]:
    """Feed ``data`` through ``get_buffer``/``buffer_updated``; what the calls returned, in
    ``out`` too, which keeps them if a call raises."""
    out = [] if out is None else out
    pos = 0
    while pos < len(data):
        protocol = isinstance(target, asyncio.BaseProtocol)  # asyncio passes a size hint
        buf = target.get_buffer(-1) if protocol else target.get_buffer()
        n = min(len(buf), len(data) - pos)
        buf[:n] = data[pos : pos + n]
        pos += n
        del buf
        result = target.buffer_updated(n)
        if result:
            out += result
    return out


def test_the_limit_is_roscpps() -> None:
    assert MAX_FRAME == 1_000_000_000
    # a subscriber that names no limit has this one
    assert inspect.signature(Subscriber).parameters["max_frame"].default == MAX_FRAME


# --- FrameReader: the reader under every TCPROS connection --------------------------------------


def test_a_prefix_of_exactly_max_frame_is_taken() -> None:
    reader = FrameReader()
    assert _feed(reader, _U32.pack(MAX_FRAME) + b"x" * 100) == []
    assert reader.mid_big_frame  # waiting for the rest of it


def test_a_prefix_one_over_max_frame_is_refused() -> None:
    with pytest.raises(FrameError, match=f"frame of {MAX_FRAME + 1} bytes exceeds the limit"):
        _feed(FrameReader(), _U32.pack(MAX_FRAME + 1) + b"x" * 100)


@pytest.mark.parametrize("limit", [100, 3 * BIG_FRAME])  # a small frame; a big one
def test_frames_of_exactly_the_limit_arrive_whole(limit: int) -> None:
    payloads = [bytes(range(256)) * (limit // 256) + b"e" * (limit % 256), b"after"]
    data = b"".join(_U32.pack(len(p)) + p for p in payloads)
    assert [bytes(f) for f in _feed(FrameReader(max_frame=limit), data)] == payloads
    over = _U32.pack(limit + 1) + b"o" * (limit + 1)
    got: list[bytes | memoryview] = []
    with pytest.raises(FrameError, match=f"exceeds the limit of {limit}") as err:
        _feed(FrameReader(max_frame=limit), data + over, got)
    assert [bytes(f) for f in got + err.value.frames] == payloads  # all before it


def test_a_header_of_exactly_its_limit_is_taken_and_one_over_is_not() -> None:
    reader = FrameReader(first_max=MAX_HEADER_LENGTH)
    assert _feed(reader, _U32.pack(MAX_HEADER_LENGTH) + b"x" * 100) == []
    with pytest.raises(FrameError, match=f"exceeds the limit of {MAX_HEADER_LENGTH}"):
        _feed(FrameReader(first_max=MAX_HEADER_LENGTH), _U32.pack(MAX_HEADER_LENGTH + 1))


# --- a subscriber's connection to a publisher ----------------------------------------------------


def test_a_subscription_takes_a_frame_of_max_frame() -> None:
    events = _feed(SubscriberStream(), REPLY + _U32.pack(4) + b"kept" + _U32.pack(MAX_FRAME) + b"x")
    assert [type(e) for e in events] == [Accepted, Messages]
    assert [bytes(f) for f in events[1].frames] == [b"kept"]


def test_a_subscription_fails_on_a_frame_one_over_max_frame() -> None:
    events = _feed(SubscriberStream(), REPLY + _U32.pack(4) + b"kept" + _U32.pack(MAX_FRAME + 1))
    assert [type(e) for e in events] == [Accepted, Messages, Failed]
    assert events[2].reason == f"frame of {MAX_FRAME + 1} bytes exceeds the limit of {MAX_FRAME}"


class _Receiver:
    """A subscriber with the default limit, recording what reaches it."""

    topic = "/chatter"
    max_frame = inspect.signature(Subscriber).parameters["max_frame"].default
    coalesce = 0.0
    reuse_frames = False

    def __init__(self) -> None:
        self.frames: list[bytes] = []

    def header_received(self, conn: Any) -> None:
        pass

    def frames_received(self, frames: list[Any], conn: Any, now: float) -> None:
        self.frames += [bytes(f) for f in frames]

    def connection_closed(self, conn: Any) -> None:
        pass


@pytest.mark.parametrize("length", [MAX_FRAME, MAX_FRAME + 1])
def test_an_inbound_connection_drops_only_a_frame_over_max_frame(length: int) -> None:
    async def run() -> tuple[InboundConnection, FakeTransport, _Receiver]:
        receiver = _Receiver()
        conn = InboundConnection(receiver, "http://p:1/", 1, b"")
        transport = FakeTransport()
        conn.connection_made(transport)
        _feed(conn, REPLY + _U32.pack(4) + b"kept" + _U32.pack(length) + b"x" * 10)
        conn._handshake_over()  # the handshake timer must not outlive the loop
        return conn, transport, receiver

    conn, transport, receiver = asyncio.run(run())
    assert receiver.frames == [b"kept"]
    if length == MAX_FRAME:
        assert not transport.closed and conn.failure is None
        assert conn.session.reader.mid_big_frame
    else:
        assert transport.closed and conn.failure is not None
        assert conn.failure.reason == f"frame of {length} bytes exceeds the limit of {MAX_FRAME}"


# --- a connection a node's TCPROS server accepted (a service client's requests) ---------------


@pytest.mark.parametrize("length", [MAX_FRAME, MAX_FRAME + 1])
def test_a_server_connection_closes_only_on_a_frame_over_max_frame(length: int) -> None:
    handler = FrameHandler()
    request = encode_header({"callerid": "/c", "service": "/s", "md5sum": "*"})

    async def run() -> FakeTransport:
        conn = ServerConnection(lambda fields, conn: handler)
        transport = FakeTransport()
        conn.connection_made(transport)
        _feed(conn, request + _U32.pack(3) + b"req")
        _feed(conn, _U32.pack(length) + b"x" * 10)
        return transport

    transport = asyncio.run(run())
    assert handler.frames == [b"req"]
    assert transport.closed == (length > MAX_FRAME)


# --- a service client's replies ------------------------------------------------------------------


def test_a_service_reply_of_exactly_max_frame_is_awaited() -> None:
    reader = ResponseReader()
    header = service_reply_header("/srv", "/s", "m" * 32, "p/Add")
    assert reader.feed(header + b"\x01" + _U32.pack(MAX_FRAME) + b"x" * 10) == []
    assert reader.header is not None and reader.header["type"] == "p/Add"


def test_a_service_reply_one_over_max_frame_is_refused() -> None:
    header = service_reply_header("/srv", "/s", "m" * 32, "p/Add")
    refusal = f"service response of {MAX_FRAME + 1} bytes exceeds the limit"
    with pytest.raises(FrameError, match=refusal):
        ResponseReader().feed(header + b"\x01" + _U32.pack(MAX_FRAME + 1))


def test_a_service_reply_header_at_and_over_max_frame() -> None:
    assert ResponseReader().feed(_U32.pack(MAX_FRAME) + b"x" * 10) == []
    refusal = f"reply header of {MAX_FRAME + 1} bytes exceeds the limit"
    with pytest.raises(FrameError, match=refusal):
        ResponseReader().feed(_U32.pack(MAX_FRAME + 1) + b"x" * 10)


@pytest.mark.parametrize("limit", [1000, 3 * BIG_FRAME])  # over the reply header's length
def test_service_replies_of_exactly_the_limit_arrive_whole(limit: int) -> None:
    payload = bytes(range(256)) * (limit // 256) + b"e" * (limit % 256)
    header = service_reply_header("/srv", "/s", "m" * 32, "p/Add")
    reply = header + b"\x01" + _U32.pack(limit) + payload
    assert ResponseReader(max_frame=limit).feed(reply) == [(True, payload)]
    reader = ResponseReader(max_frame=limit)
    assert reader.feed(reply + b"\x01" + _U32.pack(limit + 1)) == [(True, payload)]
    with pytest.raises(FrameError, match="exceeds the limit"):
        reader.feed(b"")  # the next read says it
