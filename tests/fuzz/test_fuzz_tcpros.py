"""Fuzz TCPROS in both roles: headers, frames, and the connections that read them.

The invariant: bytes from a peer end in frames, a ``FrameError``, or a closed connection
with a reason; never another exception, and never a buffer sized by what a prefix claims.
"""

from __future__ import annotations

import asyncio
import struct
from typing import Any

from hypothesis import given, seed
from hypothesis import strategies as st

from rostools.node.connection import InboundConnection, ServerConnection
from rostools.wire.header import HeaderError, decode_fields, encode_header
from rostools.wire.tcpros import (
    GROW_FIRST,
    FrameError,
    FrameReader,
    ResponseReader,
    check_service_request,
    check_subscription,
    parse_header,
)
from tests.fuzz.conftest import FUZZ, SEED

LENGTHS = st.sampled_from([0, 1, 3, 4, 100, 65536, 0x7FFFFFFF, 0xFFFFFFFF]) | st.integers(
    0, 2**32 - 1
)
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


@seed(SEED)
@FUZZ
@given(PARTS, st.binary(max_size=50), st.lists(st.integers(1, 5000), max_size=10))
def test_frame_reader_takes_any_stream(parts: list[Any], tail: bytes, cuts: list[int]) -> None:
    data = stream(parts) + tail
    reader = FrameReader(max_frame=1_000_000, first_max=100_000)
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
                reader.buffer_updated(n)
    except FrameError:
        pass


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


@seed(SEED)
@FUZZ
@given(st.binary(max_size=300), st.lists(st.integers(1, 64), max_size=6))
def test_service_responses_take_any_bytes(data: bytes, cuts: list[int]) -> None:
    reader = ResponseReader()
    pos = 0
    try:
        for cut in [*cuts, len(data)]:
            reader.feed(data[pos : pos + cut])
            pos += cut
    except FrameError:
        pass


class _Transport(asyncio.Transport):
    """Enough of a transport to feed a protocol bytes and see it close."""

    def __init__(self) -> None:
        super().__init__()
        self.closed = False
        self.written = b""

    def write(self, data: Any) -> None:
        self.written += bytes(data)

    def close(self) -> None:
        self.closed = True

    def abort(self) -> None:
        self.closed = True

    def is_closing(self) -> bool:
        return self.closed

    def get_extra_info(self, name: str, default: Any = None) -> Any:
        return ("127.0.0.1", 1) if name == "peername" else default

    def set_write_buffer_limits(self, high: Any = None, low: Any = None) -> None:
        pass


class _Subscriber:
    """What an inbound connection reports to."""

    topic = "/t"
    max_frame = 1_000_000
    coalesce = 0.0
    reuse_frames = False

    def __init__(self) -> None:
        self.frames = 0

    def header_received(self, conn: Any) -> None:
        pass

    def frames_received(self, frames: list[Any], conn: Any, now: float) -> None:
        self.frames += len(frames)

    def connection_closed(self, conn: Any) -> None:
        pass


def _feed(protocol: Any, data: bytes, cuts: list[int]) -> None:
    pos = 0
    for cut in [*cuts, len(data)]:
        while pos < len(data) and cut > 0:
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
        accepted: list[dict[str, str]] = []
        server = ServerConnection(lambda fields, conn: accepted.append(fields))
        server.connection_made(_Transport())
        _feed(server, data, cuts)
        inbound = InboundConnection(_Subscriber(), "http://p:1/", 1, b"")  # type: ignore[arg-type]
        transport = _Transport()
        inbound.connection_made(transport)
        _feed(inbound, data, cuts)
        if transport.closed:
            assert inbound.failure is not None and inbound.failure.reason

    asyncio.run(run())
