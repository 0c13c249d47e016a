"""TCPROS framing and headers, sans-IO."""

from __future__ import annotations

import struct
import threading
import tracemalloc
from collections.abc import Callable

import pytest
from hypothesis import given, settings, strategies as st

from rostools.wire.header import MAX_HEADER_LENGTH, decode_fields, encode_header
from rostools.wire.tcpros import (
    BIG_FRAME,
    GROW_FIRST,
    SCRATCH,
    Accepted,
    Event,
    Failed,
    FrameError,
    FrameReader,
    Messages,
    SubscriberStream,
    check_subscription,
    publisher_header,
    subscriber_header,
)


def feed(reader: FrameReader, data: bytes, chunk: int) -> list[bytes]:
    out: list[bytes] = []
    pos = 0
    while pos < len(data):
        buf = reader.get_buffer()
        n = min(chunk, len(buf), len(data) - pos)
        buf[:n] = data[pos : pos + n]
        pos += n
        out += [bytes(f) for f in reader.buffer_updated(n)]
    return out


def framed(payloads: list[bytes]) -> bytes:
    return b"".join(struct.pack("<I", len(p)) + p for p in payloads)


@settings(max_examples=60, deadline=None)
@given(
    st.lists(
        st.one_of(
            st.binary(max_size=300), st.integers(BIG_FRAME, 3 * BIG_FRAME).map(lambda n: b"x" * n)
        ),
        max_size=20,
    ),
    st.sampled_from([3, 4096, 1 << 20]),
)
def test_frames_survive_any_chunking(payloads: list[bytes], chunk: int) -> None:
    assert feed(FrameReader(), framed(payloads), chunk) == payloads


def test_scratch_buffer_compacts_without_losing_bytes() -> None:
    payloads = [bytes([i % 256]) * (1000 + i) for i in range(600)]  # > many scratch buffers
    assert feed(FrameReader(), framed(payloads), 65536) == payloads


def test_oversized_frame_is_refused() -> None:
    reader = FrameReader(max_frame=100)
    buf = reader.get_buffer()
    buf[:4] = struct.pack("<I", 101)
    with pytest.raises(FrameError, match="exceeds the limit"):
        reader.buffer_updated(4)


def test_rostopic_echo_header_bytes() -> None:
    """The captured rospy subscriber header (captured from rospy), field for field."""
    raw = subscriber_header(
        "/rostopic_17831_1795329627298",
        "/chatter",
        "992ce8a1687cec8c8bd883ec73ca41d1",
        "std_msgs/String",
        "string data\n",
        False,
    )
    assert raw[:4] == bytes.fromhex("b3000000")
    assert raw[4:8] == bytes.fromhex("26000000")
    assert raw.endswith(b"type=std_msgs/String")


def test_latched_publisher_reply_bytes() -> None:
    """The captured latched rospy publisher reply (§14.3)."""
    raw = publisher_header(
        "/talker",
        "/chatter",
        "992ce8a1687cec8c8bd883ec73ca41d1",
        "std_msgs/String",
        "string data\n",
        True,
    )
    assert raw[:4] == bytes.fromhex("9a000000") and len(raw) == 4 + 0x9A
    assert decode_fields(raw[4:])["latching"] == "1"


@pytest.mark.parametrize(
    ("fields", "problem"),
    [
        ({"topic": "/t", "md5sum": "*", "callerid": "/a"}, None),
        ({"topic": "/t", "md5sum": "abc", "callerid": "/a", "type": "x/Y"}, None),
        (
            {"topic": "/t", "md5sum": "zzz", "callerid": "/a", "type": "x/Z"},
            "topic types do not match",
        ),
        (
            {"topic": "/t", "md5sum": "zzz", "callerid": "/a"},
            "wants topic [/t] to have datatype/md5sum",
        ),
        ({"topic": "/t", "md5sum": "abc"}, "missing required field [callerid]"),
    ],
)
def test_subscription_checks(fields: dict[str, str], problem: str | None) -> None:
    found = check_subscription(fields, "/t", "abc", "x/Y")
    assert (found is None) if problem is None else (problem in (found or ""))


def test_header_fields_are_sorted_and_split_at_first_equals() -> None:
    raw = encode_header({"b": "1=2", "a": "x\ny"})
    assert decode_fields(raw[4:]) == {"a": "x\ny", "b": "1=2"}
    assert raw[8:13] == b"a=x\ny"


def test_service_response_reader_in_any_chunks() -> None:
    from rostools.wire.tcpros import ResponseReader, service_reply_header, service_response

    stream = (
        service_reply_header("/srv_node", "/add", "6a2e34150c00229791cc89ff309fff21", "p/Add")
        + service_response(True, b"\x07" + bytes(7))
        + service_response(False, b"bad logger")
        + service_response(True, b"")
    )
    for chunk in (1, 3, len(stream)):
        reader = ResponseReader()
        got = []
        for i in range(0, len(stream), chunk):
            got += reader.feed(stream[i : i + chunk])
        assert reader.header is not None and reader.header["type"] == "p/Add"
        assert reader.header["request_type"] == "p/AddRequest"
        assert got == [(True, b"\x07" + bytes(7)), (False, b"bad logger"), (True, b"")]


def test_captured_service_bytes() -> None:
    """Captured service replies: empty success, roscpp false, rospy ServiceException."""
    from rostools.wire.tcpros import FrameError, ResponseReader, service_response

    assert service_response(True, b"") == bytes.fromhex("0100000000")
    assert service_response(False, b"") == bytes.fromhex("0000000000")
    text = b"service cannot process request: bad logger"
    assert service_response(False, text)[:5] == bytes.fromhex("002a000000")
    reader = ResponseReader()
    reader.header = {}
    with pytest.raises(FrameError, match="status byte"):
        reader.feed(b"\x07\x00\x00\x00\x00")


def test_a_response_before_bad_bytes_in_one_read_is_kept() -> None:
    # the defect: the error raised for the bad bytes took the good response before them with
    # it (found by the TCPROS fuzz suite once it checked what comes out); rospy returns it
    from rostools.wire.tcpros import FrameError, ResponseReader, service_response

    for bad in (b"\x07\x00\x00\x00\x00", b"\x01" + struct.pack("<I", 1001)):
        reader = ResponseReader(max_frame=1000)
        reader.header = {}
        assert reader.feed(service_response(True, b"ok") + bad) == [(True, b"ok")]
        with pytest.raises(FrameError, match=r"status byte|exceeds the limit"):
            reader.feed(b"")
        with pytest.raises(FrameError):  # and again: nothing follows
            reader.feed(service_response(True, b"late"))


def test_service_request_checks() -> None:
    from rostools.wire.tcpros import check_service_request

    ok = {"callerid": "/c", "service": "/s", "md5sum": "*"}
    assert check_service_request(ok, "/s", "abc") is None
    bad = {**ok, "md5sum": "zzz"}
    assert "md5sums do not match: [zzz] vs. [abc]" in (
        check_service_request(bad, "/s", "abc") or ""
    )
    assert "missing required field [callerid]" in (
        check_service_request({"service": "/s", "md5sum": "*"}, "/s", "abc") or ""
    )


def test_a_length_prefix_alone_allocates_little() -> None:
    # the defect: a frame announcing 999,999,999 bytes got a zero-filled buffer of that size
    # before any of it arrived (981 MB for topic echo; rostopic echo stays at 38 MB)
    reader = FrameReader()
    buf = reader.get_buffer()
    buf[:24] = struct.pack("<I", 999_999_999) + b"x" * 20
    assert reader.buffer_updated(24) == []
    assert len(reader.get_buffer()) <= GROW_FIRST


def test_a_big_frame_grows_as_it_arrives() -> None:
    payload = bytes(range(256)) * (5 * GROW_FIRST // 256 + 3)  # five growths
    assert feed(FrameReader(), framed([payload, b"after"]), 300_000) == [payload, b"after"]


def test_the_first_frame_has_its_own_limit() -> None:
    # the defect: a message over the header limit, arriving in the same read as the header,
    # was refused as if it were the header
    header, message = b"h" * 10, b"m" * 200
    reader = FrameReader(max_frame=1000, first_max=100)
    assert feed(reader, framed([header, message]), 1 << 20) == [header, message]
    with pytest.raises(FrameError, match="exceeds the limit of 100"):
        feed(FrameReader(max_frame=1000, first_max=100), framed([message]), 1 << 20)


def _session_events(data: bytes, chunk: int, max_frame: int = 1 << 20) -> list[Event]:
    """Feed ``data`` to a SubscriberStream in chunks; every event, in order (no socket)."""
    session = SubscriberStream(max_frame)
    events: list[Event] = []
    pos = 0
    while pos < len(data):
        buf = session.get_buffer()  # as a socket's recv_into: at most what it offers
        piece = data[pos : pos + min(chunk, len(buf))]
        buf[: len(piece)] = piece
        pos += len(piece)
        events += session.buffer_updated(len(piece))
    return events


@pytest.mark.parametrize("chunk", [1, 7, 4096])
def test_a_subscription_takes_the_header_then_messages(chunk: int) -> None:
    reply = publisher_header("/talker", "/chatter", "m" * 32, "std_msgs/String", "", False)
    events = _session_events(reply + framed([b"one", b"", b"three"]), chunk)
    assert isinstance(events[0], Accepted) and events[0].header["callerid"] == "/talker"
    got = [bytes(f) for e in events[1:] if isinstance(e, Messages) for f in e.frames]
    assert got == [b"one", b"", b"three"]


@pytest.mark.parametrize(
    ("reply", "reason"),
    [
        (encode_header({"error": "md5 mismatch"}), "it refused us: md5 mismatch"),
        (encode_header({"callerid": "/x"}), "reply header lacks md5sum or type"),
        (struct.pack("<I", 3) + b"abc", "bad connection header"),
    ],
)
def test_a_refusal_or_a_bad_header_fails_the_subscription(reply: bytes, reason: str) -> None:
    events = _session_events(reply + framed([b"ignored"]), 4096)
    assert len(events) == 1 and isinstance(events[0], Failed), events
    assert events[0].reason.startswith(reason)


def test_an_oversized_frame_fails_after_the_messages_before_it() -> None:
    reply = publisher_header("/t", "/c", "m" * 32, "std_msgs/String", "", False)
    data = reply + framed([b"kept"]) + struct.pack("<I", 1 << 21)
    events = _session_events(data, 4096)
    assert [type(e) for e in events] == [Accepted, Messages, Failed]
    assert "exceeds the limit" in events[2].reason  # type: ignore[union-attr]
    assert _session_events(data + framed([b"late"]), 4096)[3:] == []  # nothing after Failed


def test_reused_big_buffer_holds_each_frame_and_no_more() -> None:
    """``reuse``: a shorter big frame in the longer spare buffer must not swallow the next."""
    payloads = [b"a" * (3 * BIG_FRAME), b"b" * (2 * BIG_FRAME), b"c" * 10, b"d" * (2 * BIG_FRAME)]
    reader = FrameReader()
    reader.reuse = True
    seen: list[int] = []
    out: list[bytes] = []
    data, pos = framed(payloads), 0
    while pos < len(data):
        buf = reader.get_buffer()
        n = min(48 * 1024, len(buf), len(data) - pos)  # a loopback read's size
        buf[:n] = data[pos : pos + n]
        pos += n
        for f in reader.buffer_updated(n):
            if isinstance(f, memoryview):
                seen.append(id(f.obj))
            out.append(bytes(f))  # copied during the call, as a reusing consumer must
    assert out == payloads
    assert len(seen) == 3 and len(set(seen)) == 1  # one buffer for all three big frames


# --- memory per connection (issue 24) ---------------------------------------------------------


def _held_each(make: Callable[[], object], count: int = 200) -> float:
    """Bytes that each of ``count`` results of ``make()`` keeps allocated (tracemalloc)."""
    tracemalloc.start()
    try:
        before = tracemalloc.get_traced_memory()[0]
        kept = [make() for _ in range(count)]
        held = tracemalloc.get_traced_memory()[0] - before
    finally:
        tracemalloc.stop()
    del kept
    return held / count


def _fed(data: bytes, first_max: int | None = None) -> FrameReader:
    """A reader that has received ``data`` in one read."""
    reader = FrameReader(first_max=first_max)
    reader.get_buffer()[: len(data)] = data
    reader.buffer_updated(len(data))
    return reader


def test_a_reader_between_reads_holds_no_scratch_buffer() -> None:
    # the defect: every connection owned a 256 KiB buffer from the moment it was accepted, so
    # 4,000 idle connections cost a node 1 GB (a reader after its header: 262 KB each)
    header = publisher_header("/t", "/c", "m" * 32, "std_msgs/String", "string data", False)
    assert _held_each(FrameReader) < 1024
    assert _held_each(lambda: _fed(header + b"\x05\x00")) < 2048  # and 2 bytes of a prefix


def test_a_read_that_ends_without_data_takes_no_buffer() -> None:
    # the defect: get_buffer for a read that found the end of the stream (1,000 publishers
    # closing at once) took a 256 KiB buffer each, which nothing gave back
    def eof() -> FrameReader:
        reader = FrameReader()
        reader.get_buffer()
        return reader

    assert _held_each(eof) < 1024


def test_a_frame_cut_short_costs_what_has_arrived() -> None:
    # the defect: the rest of a small frame waited in the 256 KiB buffer, and a header that
    # announced 900 KB got 1 MiB before its data came
    small = struct.pack("<I", 60_000) + b"x" * 5000
    assert _held_each(lambda: _fed(small)) < 12_000
    header = struct.pack("<I", 900_000) + b"x" * 100
    assert _held_each(lambda: _fed(header, first_max=MAX_HEADER_LENGTH)) < 12_000


def test_a_busy_read_keeps_the_buffer_until_the_socket_is_drained() -> None:
    """A read that fills the buffer keeps it (more is waiting); a shorter one gives it back."""
    payloads = [bytes([i % 256]) * 1000 for i in range(300)]  # more than a buffer
    data, reader = framed(payloads), FrameReader()
    buf = reader.get_buffer()
    assert len(buf) == SCRATCH
    buf[:] = data[:SCRATCH]
    got = [bytes(f) for f in reader.buffer_updated(SCRATCH)]
    assert reader.holds_scratch  # it ended mid-frame, and the socket may hold the rest
    rest = data[SCRATCH:]
    reader.get_buffer()[: len(rest)] = rest
    got += [bytes(f) for f in reader.buffer_updated(len(rest))]
    assert not reader.holds_scratch
    assert got == payloads


@settings(max_examples=60, deadline=None)
@given(
    st.lists(st.tuples(st.booleans(), st.integers(1, 5000), st.booleans()), max_size=60),
    st.lists(st.binary(max_size=6000), min_size=1, max_size=12),
    st.lists(st.binary(max_size=6000), min_size=1, max_size=12),
)
def test_readers_that_share_the_lent_buffer_keep_their_own_bytes(
    steps: list[tuple[bool, int, bool]], first: list[bytes], second: list[bytes]
) -> None:
    """Two connections read in turns from one thread's buffer; some reads find nothing."""
    streams = [framed(first), framed(second)]
    readers, got = [FrameReader(), FrameReader()], [list[bytes](), list[bytes]()]
    pos = [0, 0]
    for which, size, empty in [*steps, *((w, 1 << 20, False) for w in (0, 1) for _ in range(30))]:
        i = int(which)
        buf = readers[i].get_buffer()
        if empty or pos[i] == len(streams[i]):
            continue  # the read found nothing (end of stream, a spurious wake-up)
        n = min(size, len(buf), len(streams[i]) - pos[i])
        buf[:n] = streams[i][pos[i] : pos[i] + n]
        pos[i] += n
        got[i] += [bytes(f) for f in readers[i].buffer_updated(n)]
    assert got == [first, second]


def test_readers_in_two_threads_do_not_share_a_buffer() -> None:
    """A read under way in one thread is not overwritten by a read in another."""
    message = framed([b"from the first thread"])
    made: list[FrameReader] = []
    lent = threading.Event()
    other_done = threading.Event()
    got: list[bytes] = []

    def first() -> None:
        reader = FrameReader()
        buf = reader.get_buffer()
        buf[: len(message)] = message
        lent.set()
        other_done.wait(10)  # the other thread reads meanwhile, in the middle of ours
        got.extend(bytes(f) for f in reader.buffer_updated(len(message)))

    def second() -> None:
        lent.wait(10)
        made.append(FrameReader())
        other = framed([b"x" * 100] * 10)
        made[0].get_buffer()[: len(other)] = other
        made[0].buffer_updated(len(other))
        other_done.set()

    threads = [threading.Thread(target=first), threading.Thread(target=second)]
    for t in threads:
        t.start()
    for t in threads:
        t.join(20)
    assert got == [b"from the first thread"]
