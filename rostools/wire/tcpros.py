"""TCPROS, sans-IO: connection headers, frame splitting into reusable buffers, validation.

``FrameReader`` is the receive half of every TCPROS connection. It follows the asyncio
``BufferedProtocol`` shape (``get_buffer``/``buffer_updated``) without doing any IO: small
frames are received many at a time into a scratch buffer and copied out once; a large
frame gets a buffer of exactly its size, filled in place and handed over without a copy.
That is what lets Python receive at the speed the socket allows (benchmarks/bench_topic.py).

The scratch buffer is not a connection's own: each thread that reads has one, lent to a
connection for one read at a time. Between reads a connection holds only the part of a
frame that has arrived, so an idle connection costs no buffer, and a closed one leaves
none behind.
"""

from __future__ import annotations

import struct
import threading
from typing import NamedTuple

from rostools.wire.header import MAX_HEADER_LENGTH, HeaderError, decode_fields, encode_header

_U32 = struct.Struct("<I")

#: roscpp drops a connection whose frame length exceeds 1e9 bytes (``Connection::read``).
MAX_FRAME = 1_000_000_000
#: Seconds a new connection has to complete its header exchange. rospy and roscpp wait
#: forever, so a peer that connects and sends nothing holds its buffers for good; a real peer
#: sends its header at once.
HANDSHAKE_TIMEOUT = 10.0
#: Frames at least this big are received into a buffer of their own, not the scratch buffer.
BIG_FRAME = 64 * 1024
#: The scratch buffer: many small frames per recv; several times BIG_FRAME so it never fills
#: with a partial small frame.
SCRATCH = 256 * 1024
#: A big frame's buffer starts this big (or at what has arrived) and doubles as data comes:
#: what a length prefix alone can make us allocate. 1 MiB holds a 1 MB image without growing.
GROW_FIRST = 1024 * 1024
#: A small frame cut short by the end of what the socket had waits as a copy while this
#: much of it has come, in a buffer of its own (this big, then doubling) once more has: the
#: scratch buffer is free for the next read either way, and a frame that trickles in a byte
#: at a time is not copied whole at every byte. A connection header over BIG_FRAME starts
#: this big too, not at GROW_FIRST: the largest real one is 10.6 KB, and a peer that has not
#: said who it is should cost us little more than what it sent.
PARTIAL_FIRST = 4096


class Scratch:
    """A thread's scratch buffer, lent to one connection's read at a time.

    Every asyncio transport (selector, proactor, uvloop) calls ``buffer_updated`` or ends the
    read (end of stream, an error, nothing to read) before it asks any protocol of its thread
    for a buffer again, so a buffer lent for one read is free at the next ``get_buffer``.
    Before it was lent, each connection owned 256 KiB from the moment it was accepted:
    4,000 idle connections cost a node 1 GB, which stayed after they closed.
    """

    __slots__ = ("view",)

    def __init__(self) -> None:
        #: The buffer, made at the first read; None while a busy connection keeps it.
        self.view: memoryview | None = None


_threads = threading.local()


def thread_scratch() -> Scratch:
    """The calling thread's ``Scratch``."""
    try:
        scratch: Scratch = _threads.scratch
    except AttributeError:
        scratch = _threads.scratch = Scratch()
    return scratch


class FrameError(ValueError):
    """A frame the peer should not have sent (too long, a bad header).

    ``frames`` holds the frames completed before it in the same read: they were sent first.
    """

    def __init__(self, message: str, frames: list[bytes | memoryview] | None = None) -> None:
        super().__init__(message)
        self.frames: list[bytes | memoryview] = frames or []


def frame(payload: bytes) -> bytes:
    """``payload`` as one TCPROS frame: its length prefix, then itself."""
    return _U32.pack(len(payload)) + payload


def frame_prefix(length: int) -> bytes:
    """The 4-byte length that precedes every TCPROS frame."""
    return _U32.pack(length)


class FrameReader:
    """Splits a byte stream into frames, receiving into reusable buffers.

    A frame's length prefix is not trusted: the buffer of a big frame starts at what has
    arrived, at least ``GROW_FIRST`` (``PARTIAL_FIRST`` for the first frame), and doubles
    as more arrives, so a peer that announces a gigabyte and sends twenty bytes costs us a
    megabyte, not a gigabyte. The first frame of a connection (its header) may have a limit
    of its own, ``first_max``.

    Each read goes to the scratch buffer of the thread that made the reader (``Scratch``),
    so a reader reads in that thread, as an asyncio protocol does. The start of a frame that
    is not complete then waits as a copy (``_tail``), or in a buffer of its own that grows as
    it arrives (``PARTIAL_FIRST``). A read that filled the scratch buffer keeps it instead
    (``_own``), as more is surely waiting: a busy connection reads into one buffer, and the
    thread makes itself another.
    """

    __slots__ = (
        "_big", "_big_filled", "_big_length", "_end", "_lender", "_own", "_spare", "_start",
        "_tail", "_view", "first_max", "max_frame", "reuse",
    )  # fmt: skip

    def __init__(self, max_frame: int = MAX_FRAME, first_max: int | None = None) -> None:
        self.max_frame = max_frame
        #: The limit of the next frame only, while it is the first; then ``max_frame``.
        self.first_max = first_max
        #: The scratch buffer of the read under way (lent or our own); ``_start``, ``_end``:
        #: the bytes in it not yet split into frames.
        self._view: memoryview | None = None
        self._start = 0
        self._end = 0
        #: A scratch buffer kept between reads while the connection is busy.
        self._own: memoryview | None = None
        #: The start of a frame, kept between reads while no scratch buffer is.
        self._tail = b""
        self._lender = thread_scratch()  # looked up once: a thread-local costs 80 ns a read
        self._big: bytearray | None = None
        self._big_filled = 0
        self._big_length = 0
        #: Receive every big frame into one buffer, for a consumer that is done with each
        #: frame when its call returns (hz, bw): no allocation and no page faults per frame.
        self.reuse = False
        self._spare: bytearray | None = None

    def get_buffer(self) -> memoryview:
        """Where the next bytes from the socket go."""
        big = self._big
        if big is not None:
            if self._big_filled == len(big):  # full, but the frame is not: double it
                size = min(self._big_length, 2 * len(big))
                try:
                    big.extend(bytes(size - len(big)))  # in place (realloc), between reads
                except BufferError:  # a view of the last read is still alive: copy instead
                    grown = bytearray(size)
                    grown[: len(big)] = big
                    self._big = big = grown
            return memoryview(big)[self._big_filled : self._big_length]  # a spare may be longer
        view = self._own
        if view is not None:
            if self._end == SCRATCH:
                # Compact: the partial frame left at the end moves to the front.
                pending = self._end - self._start
                view[:pending] = view[self._start : self._end]
                self._start, self._end = 0, pending
            return view[self._end :]
        lender = self._lender
        view = lender.view
        if view is None:
            view = lender.view = memoryview(bytearray(SCRATCH))
        self._view = view  # _start and _end are 0 between lent reads
        # The tail stays ours until the read is accounted for: a read that ends without
        # ``buffer_updated`` (nothing to read after all) must not lose it.
        tail = self._tail
        if tail:
            self._end = n = len(tail)
            view[:n] = tail
            return view[n:]
        return view

    @property
    def holds_scratch(self) -> bool:
        """Whether a scratch buffer is kept between reads (the last read filled it)."""
        return self._own is not None

    @property
    def mid_big_frame(self) -> bool:
        """Whether a big frame has begun and not yet ended."""
        return self._big is not None

    def buffer_updated(self, nbytes: int) -> list[bytes | memoryview]:
        """Account for ``nbytes`` received; every frame now complete, in order.

        Small frames come out as ``bytes`` copies; a big frame comes out as a view of a buffer
        that is never reused (unless ``reuse``). Either stays valid after the call.
        """
        if self._big is not None:
            return self._fill_big(nbytes)
        view = self._view
        assert view is not None, "buffer_updated without get_buffer"
        self._end += nbytes
        frames: list[bytes | memoryview] = []
        start, end = self._start, self._end
        # One copy of everything received, then each frame is a slice of it: slicing bytes is
        # one allocation, where slicing the buffer costs a memoryview and a bytes.
        data = bytes(view[start:end])
        size, pos = end - start, 0  # ``pos`` is where the next frame starts in ``data``
        unpack = _U32.unpack_from
        append = frames.append
        limit = self.max_frame if self.first_max is None else self.first_max
        while size - pos >= 4:
            (length,) = unpack(data, pos)
            if length > limit:
                raise FrameError(f"frame of {length} bytes exceeds the limit of {limit}", frames)
            after = pos + 4 + length
            if after <= size:
                append(data[pos + 4 : after])
                pos = after
                limit = self.max_frame
            elif length >= BIG_FRAME or (end < SCRATCH and size - pos - 4 > PARTIAL_FIRST):
                # A big frame, or much of one cut short by the end of what the socket had: it
                # waits in a buffer of its own, filled in place by the next reads.
                self._begin_big(view[start + pos + 4 : end], length, pos == 0)
                pos = size
                break
            else:
                break
        if pos:
            self.first_max = None  # the first frame is done, or is a big one under way
        self._keep_rest(view, data, pos, size)
        return frames

    def _fill_big(self, nbytes: int) -> list[bytes | memoryview]:
        """Account for ``nbytes`` more of the big frame under way; the frame once complete."""
        assert self._big is not None
        self._big_filled += nbytes
        if self._big_filled < self._big_length:
            return []
        if self.reuse:
            self._spare = self._big
            done = memoryview(self._big)[: self._big_length].toreadonly()
        else:
            # Read-only: nobody writes to it again, and writers may keep it without a copy.
            done = memoryview(self._big).toreadonly()
        self._big = None
        return [done]

    def _begin_big(self, have: memoryview, length: int, at_start: bool) -> None:
        """Start a frame of ``length`` bytes in a buffer of its own, with what came of it."""
        spare = self._spare
        if self.reuse and spare is not None and len(spare) >= length:
            self._big = spare
        else:
            header = at_start and self.first_max is not None
            first = PARTIAL_FIRST if length < BIG_FRAME or header else GROW_FIRST
            self._big = bytearray(min(length, max(first, len(have))))
        self._big[: len(have)] = have
        self._big_filled, self._big_length = len(have), length

    def _keep_rest(self, view: memoryview, data: bytes, pos: int, size: int) -> None:
        """After a read: keep its partial frame, in the scratch buffer or as the tail."""
        if pos < size and self._end == SCRATCH:
            # More is waiting: keep the buffer and its partial frame.
            if self._own is None:
                self._own = view
                if self._lender.view is view:
                    self._lender.view = None  # the thread makes itself another
            self._start += pos
            return
        self._tail = data[pos:] if pos < size else b""  # at most PARTIAL_FIRST + 4 bytes
        self._end = 0
        if self._own is not None:
            self._start = 0
            if self._lender.view is None:
                self._lender.view = self._own
            self._own = None


class Accepted(NamedTuple):
    """The publisher's header, checked: messages follow."""

    header: dict[str, str]


class Messages(NamedTuple):
    """Complete messages, raw, in order."""

    frames: list[bytes | memoryview]


class Failed(NamedTuple):
    """The connection is done for: refused, malformed, or a frame over the limit."""

    reason: str


Event = Accepted | Messages | Failed


class SubscriberStream:
    """A subscriber's end of one TCPROS connection, sans-IO: bytes in, events out.

    Feed it what the socket receives (``get_buffer``/``buffer_updated``, the shape of
    asyncio's ``BufferedProtocol``). The first frame is the publisher's header: ``Accepted``
    when it names an md5sum and a type, else ``Failed``, with the publisher's own reason when
    it refused us. Then each read's complete messages come out as one ``Messages``. A frame
    over ``max_frame`` is ``Failed``, after the messages before it. Nothing follows ``Failed``.
    """

    __slots__ = ("failed", "header", "reader")

    def __init__(self, max_frame: int = MAX_FRAME) -> None:
        self.reader = FrameReader(max_frame, first_max=MAX_HEADER_LENGTH)
        self.header: dict[str, str] | None = None
        self.failed = False

    def get_buffer(self) -> memoryview:
        """Where the next bytes from the socket go."""
        return self.reader.get_buffer()

    def buffer_updated(self, nbytes: int) -> list[Event]:
        """Account for ``nbytes`` received; what they completed."""
        if self.failed:
            return []
        error: FrameError | None = None
        try:
            frames = self.reader.buffer_updated(nbytes)
        except FrameError as err:
            frames, error = err.frames, err  # the frames before the bad one still count
        events: list[Event] = []
        if frames and self.header is None:
            header = _checked_reply(frames[0])
            if isinstance(header, str):
                self.failed = True
                return [Failed(header)]
            self.header = header
            events.append(Accepted(header))
            frames = frames[1:]
        if frames:
            events.append(Messages(frames))
        if error is not None:
            self.failed = True
            events.append(Failed(str(error)))
        return events


def _checked_reply(first: bytes | memoryview) -> dict[str, str] | str:
    """A publisher's reply header, or why it is refused."""
    try:
        header = parse_header(first)
    except FrameError as err:
        return str(err)
    if "error" in header:
        return f"it refused us: {header['error']}"
    if "md5sum" not in header or "type" not in header:
        return "reply header lacks md5sum or type"
    return header


def parse_header(frame: bytes | memoryview) -> dict[str, str]:
    """A connection header's fields (the frame after its length prefix)."""
    try:
        return decode_fields(frame)
    except HeaderError as err:
        raise FrameError(f"bad connection header: {err}") from err


def error_header(message: str) -> bytes:
    """The header that refuses a connection: a lone ``error`` field."""
    return encode_header({"error": message})


def subscriber_header(
    caller_id: str, topic: str, md5sum: str, type_name: str, definition: str, tcp_nodelay: bool
) -> bytes:
    """What a subscriber sends first (rospy's fields)."""
    return encode_header(
        {
            "callerid": caller_id,
            "topic": topic,
            "md5sum": md5sum,
            "type": type_name,
            "message_definition": definition,
            "tcp_nodelay": "1" if tcp_nodelay else "0",
        }
    )


def publisher_header(
    caller_id: str, topic: str, md5sum: str, type_name: str, definition: str, latching: bool
) -> bytes:
    """A publisher's reply: exactly the fields rospy and roscpp send."""
    return encode_header(
        {
            "callerid": caller_id,
            "latching": "1" if latching else "0",
            "md5sum": md5sum,
            "message_definition": definition,
            "topic": topic,
            "type": type_name,
        }
    )


def check_subscription(
    fields: dict[str, str], topic: str, md5sum: str, type_name: str
) -> str | None:
    """Why a publisher refuses this subscriber's header, or None when it accepts it."""
    for required in ("topic", "md5sum", "callerid"):
        if required not in fields:
            return f"header missing required field [{required}]"
    theirs = fields["md5sum"]
    if theirs == "*" or md5sum == "*" or theirs == md5sum:
        return None
    wanted_type = fields.get("type", "*")
    if wanted_type not in ("*", type_name):
        return f"topic types do not match: [{wanted_type}] vs. [{type_name}]"
    return (
        f"Client [{fields['callerid']}] wants topic [{topic}] to have datatype/md5sum "
        f"[{wanted_type}/{theirs}], but our version has [{type_name}/{md5sum}] Dropping connection."
    )


# services ---------------------------------------------------------------------------------


def service_request_header(
    caller_id: str, service: str, md5sum: str, *, persistent: bool = False, probe: bool = False
) -> bytes:
    """What a service client sends first; md5sum ``*`` to probe for the type."""
    fields = {"callerid": caller_id, "service": service, "md5sum": md5sum}
    if persistent:
        fields["persistent"] = "1"
    if probe:
        fields["probe"] = "1"
    return encode_header(fields)


def service_reply_header(caller_id: str, service: str, md5sum: str, type_name: str) -> bytes:
    """A service server's reply: rospy's fields plus roscpp's request/response types."""
    return encode_header(
        {
            "callerid": caller_id,
            "md5sum": md5sum,
            "request_type": f"{type_name}Request",
            "response_type": f"{type_name}Response",
            "service": service,
            "type": type_name,
        }
    )


def check_service_request(fields: dict[str, str], service: str, md5sum: str) -> str | None:
    """Why a server refuses this client's header, or None when it accepts it."""
    for required in ("callerid", "service", "md5sum"):
        if required not in fields:
            return f"header missing required field [{required}]"
    theirs = fields["md5sum"]
    if theirs not in ("*", md5sum):
        return (
            f"request from [{fields['callerid']}]: md5sums do not match: [{theirs}] vs. [{md5sum}]"
        )
    return None


def service_response(ok: bool, payload: bytes) -> bytes:
    """A response: one ok byte, then a length-prefixed payload (the error text when not ok)."""
    return (b"\x01" if ok else b"\x00") + frame(payload)


class ResponseReader:
    """A service client's receive side: the reply header, then ``ok ; u32 len ; payload``.

    Bytes that are no response raise ``FrameError``; responses before them in the same bytes
    are returned first, and the error is raised by the next ``feed``.
    """

    def __init__(self, max_frame: int = MAX_FRAME) -> None:
        self.buffer = bytearray()
        self.max_frame = max_frame
        self.header: dict[str, str] | None = None
        self._error: FrameError | None = None

    def feed(self, data: bytes | memoryview) -> list[tuple[bool, bytes]]:
        """Add received bytes; the responses now complete, as (ok, payload)."""
        if self._error is not None:
            raise self._error
        if not self.buffer and self.header is not None and len(data) >= 5:
            # The usual read: exactly one whole response, parsed without buffering it.
            ok = data[0]
            (length,) = _U32.unpack_from(data, 1)
            if ok in (0, 1) and len(data) == 5 + length:
                return [(ok == 1, bytes(data[5:]))]
        self.buffer += data
        out: list[tuple[bool, bytes]] = []
        while True:
            if self.header is None:
                if len(self.buffer) < 4:
                    return out
                (length,) = _U32.unpack_from(self.buffer, 0)
                if length > self.max_frame:
                    raise FrameError(f"reply header of {length} bytes exceeds the limit")
                if len(self.buffer) < 4 + length:
                    return out
                self.header = parse_header(bytes(self.buffer[4 : 4 + length]))
                del self.buffer[: 4 + length]
                continue
            if len(self.buffer) < 5:
                return out
            ok = self.buffer[0]
            if ok not in (0, 1):
                return self._fail(out, f"bad service response status byte {ok}")
            (length,) = _U32.unpack_from(self.buffer, 1)
            if length > self.max_frame:
                return self._fail(out, f"service response of {length} bytes exceeds the limit")
            if len(self.buffer) < 5 + length:
                return out
            out.append((ok == 1, bytes(self.buffer[5 : 5 + length])))
            del self.buffer[: 5 + length]

    def _fail(self, out: list[tuple[bool, bytes]], reason: str) -> list[tuple[bool, bytes]]:
        """Raise now, or once the responses before the bad bytes are handed over."""
        self._error = FrameError(reason)
        if not out:
            raise self._error
        return out
