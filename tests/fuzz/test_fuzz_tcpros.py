"""Fuzz TCPROS in both roles: headers, frames, and the connections that read them.

The invariant: bytes from a peer end in frames, a ``FrameError``, or a closed connection
with a reason; never another exception, and never a buffer sized by what a prefix claims.
What comes out is checked against a reading of the whole stream at once (``_expected``):
every whole frame before the first one over its limit, byte for byte, in order, however
the stream is cut; a refusal exactly when a frame is over its limit.
"""

from __future__ import annotations

import asyncio
import struct
from typing import Any

from hypothesis import given, seed, strategies as st

from rostools.node.connection import InboundConnection, ServerConnection
from rostools.wire.header import MAX_HEADER_LENGTH, HeaderError, decode_fields, encode_header
from rostools.wire.tcpros import (
    GROW_FIRST,
    MAX_FRAME,
    FrameError,
    FrameReader,
    ResponseReader,
    check_service_request,
    check_subscription,
    parse_header,
)
from tests.fuzz.conftest import FUZZ, SEED
from tests.support.fakeconn import FakeTransport, FrameHandler

#: Length prefixes: small, big, huge, and each limit and one over it.
LENGTHS = st.sampled_from(
    [0, 1, 3, 4, 100, 65536, 0x7FFFFFFF, 0xFFFFFFFF]
    + [n + d for n in (100_000, 1_000_000, MAX_HEADER_LENGTH, MAX_FRAME) for d in (0, 1)]
) | st.integers(0, 2**32 - 1)
FIELDS = st.dictionaries(
    st.sampled_from(["callerid", "topic", "md5sum", "type", "service", "error", "latching", "x"])
    | st.text(max_size=10),
    st.text(max_size=30),
    max_size=6,
)


def stream(draw_parts: list[Any]) -> bytes:
    """Frames and lies: each part is bytes, a header dict, or a bare length prefix."""
    out = b""
    for part in draw_parts:
        if isinstance(part, dict):
            out += encode_header(part)
        elif isinstance(part, int):
            out += struct.pack("<I", part)
        else:
            out += struct.pack("<I", len(part)) + part
    return out


PARTS = st.lists(st.binary(max_size=300) | FIELDS | LENGTHS, max_size=8)


def _expected(data: bytes, max_frame: int, first_max: int) -> tuple[list[bytes], bool]:
    """(every whole frame, in order; whether a frame over its limit stops the stream)."""
    frames: list[bytes] = []
    pos, limit = 0, first_max
    while len(data) - pos >= 4:
        (length,) = struct.unpack_from("<I", data, pos)
        if length > limit:
            return frames, True
        if pos + 4 + length > len(data):
            break
        frames.append(data[pos + 4 : pos + 4 + length])
        pos += 4 + length
        limit = max_frame
    return frames, False


@seed(SEED)
@FUZZ
@given(PARTS, st.binary(max_size=50), st.lists(st.integers(1, 5000), max_size=10))
def test_frame_reader_takes_any_stream(parts: list[Any], tail: bytes, cuts: list[int]) -> None:
    data = stream(parts) + tail
    reader = FrameReader(max_frame=1_000_000, first_max=100_000)
    got: list[bytes] = []
    refused = False
    pos = 0
    try:
        for cut in [*cuts, len(data)]:
            while pos < len(data) and cut > 0:
                buf = reader.get_buffer()
                assert len(buf) <= max(GROW_FIRST, 4 * len(data)) + 256 * 1024
                n = min(cut, len(buf), len(data) - pos)
                buf[:n] = data[pos : pos + n]
                pos, cut = pos + n, cut - n
                del buf
                got += [bytes(f) for f in reader.buffer_updated(n)]
    except FrameError as err:
        refused = True
        got += [bytes(f) for f in err.frames]  # the whole frames before the bad one
        assert "exceeds the limit of" in str(err)
    assert (got, refused) == _expected(data, 1_000_000, 100_000)


@seed(SEED)
@FUZZ
@given(st.binary(max_size=200) | FIELDS.map(lambda f: encode_header(f)[4:]))
def test_headers_parse_or_refuse(data: bytes) -> None:
    try:
        fields = parse_header(data)
    except FrameError:
        return
    assert all(isinstance(k, str) and isinstance(v, str) for k, v in fields.items())
    check_subscription(fields, "/t", "abc", "std_msgs/String")
    check_service_request(fields, "/s", "abc")
    try:
        decode_fields(data)
    except HeaderError:
        raise AssertionError("parse_header accepted what decode_fields refuses") from None


def _expected_responses(data: bytes) -> tuple[list[tuple[bool, bytes]], bool]:
    """(every whole service response after the reply header; whether the bytes are refused)."""
    if len(data) < 4:
        return [], False
    (length,) = struct.unpack_from("<I", data)
    if length > MAX_FRAME:
        return [], True
    if len(data) < 4 + length:
        return [], False
    if _header(data[4 : 4 + length]) is None:
        return [], True
    out: list[tuple[bool, bytes]] = []
    pos = 4 + length
    while len(data) - pos >= 5:
        if data[pos] not in (0, 1):  # the status byte
            return out, True
        (length,) = struct.unpack_from("<I", data, pos + 1)
        if length > MAX_FRAME:
            return out, True
        if pos + 5 + length > len(data):
            break
        out.append((data[pos] == 1, data[pos + 5 : pos + 5 + length]))
        pos += 5 + length
    return out, False


def _header(frame: bytes) -> dict[str, str] | None:
    """A connection header's fields, or None when it does not parse."""
    try:
        return parse_header(frame)
    except FrameError:
        return None


SERVICE_PARTS = st.lists(
    FIELDS.map(encode_header)
    | st.tuples(st.sampled_from([0, 1, 2, 255]), st.binary(max_size=100)).map(
        lambda r: bytes([r[0]]) + struct.pack("<I", len(r[1])) + r[1]
    )
    | st.binary(max_size=20),
    max_size=6,
).map(b"".join)


@seed(SEED)
@FUZZ
@given(st.binary(max_size=300) | SERVICE_PARTS, st.lists(st.integers(1, 64), max_size=6))
def test_service_responses_take_any_bytes(data: bytes, cuts: list[int]) -> None:
    reader = ResponseReader()
    got: list[tuple[bool, bytes]] = []
    refused = False
    pos = 0
    try:
        for cut in [*cuts, len(data)]:
            got += reader.feed(data[pos : pos + cut])
            pos += cut
        got += reader.feed(b"")  # bad bytes after a response in one read are said next
    except FrameError:
        refused = True
    assert (got, refused) == _expected_responses(data)


class _Subscriber:
    """What an inbound connection reports to."""

    topic = "/t"
    max_frame = 1_000_000
    coalesce = 0.0
    reuse_frames = False

    def __init__(self) -> None:
        self.frames: list[bytes] = []
        self.headers = 0

    def header_received(self, conn: Any) -> None:
        self.headers += 1

    def frames_received(self, frames: list[Any], conn: Any, now: float) -> None:
        self.frames += [bytes(f) for f in frames]

    def connection_closed(self, conn: Any) -> None:
        pass


def _feed(protocol: Any, data: bytes, cuts: list[int]) -> None:
    pos = 0
    for cut in [*cuts, len(data)]:
        while pos < len(data) and cut > 0 and not protocol.transport.closed:
            buf = protocol.get_buffer(-1)
            n = min(cut, len(buf), len(data) - pos)
            buf[:n] = data[pos : pos + n]
            pos, cut = pos + n, cut - n
            del buf
            protocol.buffer_updated(n)


@seed(SEED)
@FUZZ
@given(PARTS, st.lists(st.integers(1, 3000), max_size=6))
def test_connections_in_both_roles_take_any_bytes(parts: list[Any], cuts: list[int]) -> None:
    data = stream(parts)

    async def run() -> None:
        # a node's TCPROS server: the header goes to accept, the frames after it to a handler
        frames, refused = _expected(data, MAX_FRAME, MAX_HEADER_LENGTH)
        accepted: list[dict[str, str]] = []
        handler = FrameHandler()

        def accept(fields: dict[str, str], conn: Any) -> FrameHandler:
            accepted.append(fields)
            return handler

        server = ServerConnection(accept)
        transport = FakeTransport()
        server.connection_made(transport)
        _feed(server, data, cuts)
        header = _header(frames[0]) if frames else None
        if refused:  # the frames of the read that refused are dropped with the connection
            assert accepted == [header][: len(accepted)]
        else:
            assert accepted == ([] if header is None else [header])
        if refused:
            assert handler.frames == frames[1:][: len(handler.frames)]
        else:
            assert handler.frames == (frames[1:] if header is not None else [])
        assert transport.closed == (refused or (bool(frames) and header is None))
        server._handshake_over()  # the handshake timer must not outlive the loop

        # a subscriber's connection to a publisher: the reply header, checked, then messages
        frames, refused = _expected(data, 1_000_000, MAX_HEADER_LENGTH)
        subscriber = _Subscriber()
        inbound = InboundConnection(subscriber, "http://p:1/", 1, b"")
        transport = FakeTransport()
        inbound.connection_made(transport)
        _feed(inbound, data, cuts)
        header = _header(frames[0]) if frames else None
        good = header is not None and "error" not in header and {"md5sum", "type"} <= set(header)
        assert subscriber.headers == int(good)
        assert inbound.header == (header if good else None)
        assert subscriber.frames == (frames[1:] if good else [])
        assert transport.closed == (refused or (bool(frames) and not good))
        if transport.closed:
            assert inbound.failure is not None and inbound.failure.reason
        inbound._handshake_over()

    asyncio.run(run())
