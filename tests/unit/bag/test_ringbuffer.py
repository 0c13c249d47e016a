"""``bag snapshot``'s rolling buffer: oldest out first, within its limits, latched kept."""

from __future__ import annotations

import tracemalloc

from rostools.bag.formats.model import ENTRY_OVERHEAD
from rostools.bag.live.ringbuffer import GONE_KEPT, ConnInfo, Lost, RingBuffer

NS = 1_000_000_000
A = ConnInfo("/a", {"callerid": "/pa", "type": "std_msgs/String"})
B = ConnInfo("/b", {"callerid": "/pb", "type": "std_msgs/String"})
STATIC = ConnInfo("/tf_static", {"callerid": "/ps", "latching": "1"})


def frame(text: str) -> bytes:
    return len(text).to_bytes(4, "little") + text.encode()


def texts(entries: object) -> list[str]:
    return [bytes(d[4:]).decode() for _, _, d in entries]  # type: ignore[attr-defined]


def test_the_duration_and_the_size_evict_the_oldest_of_all_topics() -> None:
    ring = RingBuffer(duration_ns=10 * NS, size=10 * (8 + ENTRY_OVERHEAD))
    for i in range(12):  # 8-byte messages, alternating topics, one a second
        conn = A if i % 2 == 0 else B
        ring.add(ring.topic(conn.topic), conn, i * NS, [frame(f"m{i:03}")])
    held = ring.copy()
    assert texts(held.messages(0, 100 * NS)) == [f"m{i:03}" for i in range(2, 12)]  # size: 10
    assert ring.topics["/a"].evicted == ring.topics["/b"].evicted == 1
    ring.evict_old(15 * NS)  # the duration: nothing older than 5 s
    assert texts(ring.copy().messages(0, 100 * NS)) == [f"m{i:03}" for i in range(5, 12)]
    assert ring.bytes == 7 * (8 + ENTRY_OVERHEAD)


def test_a_topic_limit_evicts_only_that_topic_and_the_order_holds() -> None:
    ring = RingBuffer(duration_ns=100 * NS, size=1 << 30, topic_size=3 * (8 + ENTRY_OVERHEAD))
    for i in range(20):  # /a floods, /b trickles: each keeps its last 3
        conn = B if i % 5 == 0 else A
        ring.add(ring.topic(conn.topic), conn, i * NS, [frame(f"m{i:03}")])
    got = texts(ring.copy().messages(0, 100 * NS))
    assert got == ["m005", "m010", "m015", "m017", "m018", "m019"]
    assert (ring.topics["/a"].evicted, ring.topics["/b"].evicted) == (13, 1)
    # the slots /a let go are let go from the order as they reach its front
    ring.size = 4 * (8 + ENTRY_OVERHEAD)
    ring.add(ring.topic("/b"), B, 20 * NS, [frame("m020")])
    assert texts(ring.copy().messages(0, 100 * NS)) == ["m017", "m018", "m019", "m020"]
    assert len(ring.order) == 4 and ring.bytes == 4 * (8 + ENTRY_OVERHEAD)


def test_a_copy_keeps_its_window_while_the_buffer_goes_on_evicting() -> None:
    ring = RingBuffer(duration_ns=100 * NS, size=5 * (8 + ENTRY_OVERHEAD))
    for i in range(5):
        ring.add(ring.topic("/a"), A, i * NS, [frame(f"m{i:03}")])
    held = ring.copy({"/a"})
    for i in range(5, 10):  # every message the copy holds is evicted from the buffer
        ring.add(ring.topic("/a"), A, i * NS, [frame(f"m{i:03}")])
    assert texts(held.messages(1 * NS, 3 * NS)) == ["m001", "m002", "m003"]
    ring.clear({"/a"})  # --clear-on-write
    assert not ring.copy().any_between(0, 100 * NS) and ring.bytes == 5 * ENTRY_OVERHEAD


def test_the_last_latched_message_is_kept_and_stamped_at_the_window() -> None:
    ring = RingBuffer(duration_ns=5 * NS, size=1 << 30)
    ring.add(ring.topic("/tf_static"), STATIC, 1 * NS, [frame("old"), frame("last")])
    for i in range(2, 30):
        ring.add(ring.topic("/a"), A, i * NS, [frame(f"m{i:03}")])
    assert not ring.topics["/tf_static"].entries  # the duration evicted it
    held = ring.copy()
    assert [(t, bytes(d[4:])) for t, _, d in held.latched_before(27 * NS)] == [(27 * NS, b"last")]
    assert texts(held.messages(27 * NS, 29 * NS)) == ["m027", "m028", "m029"]
    assert ring.held == ring.bytes + len(frame("last")) + ENTRY_OVERHEAD


def test_small_messages_hold_no_more_than_the_limit() -> None:
    limit = 1024 * 1024
    ring = RingBuffer(duration_ns=100 * NS, size=limit)
    tb = ring.topic("/a")
    tracemalloc.start()
    try:
        for i in range(400):  # 200,000 16-byte messages, in reads of 500
            ring.add(tb, A, i, [bytes(16) for _ in range(500)])
        held, _ = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert held < 1.25 * limit, held
    assert tb.evicted > 190_000


def test_a_latched_message_the_size_evicts_is_given_back_in_its_window() -> None:
    """Evicted by --size (not by age) inside the window asked for: still written, not lost."""
    ring = RingBuffer(duration_ns=100 * NS, size=4 * (8 + ENTRY_OVERHEAD) + 200)
    ring.add(ring.topic("/tf_static"), STATIC, 5 * NS, [frame("tf")])
    for i in range(6, 16):
        ring.add(ring.topic("/a"), A, i * NS, [frame(f"m{i:03}")])
    assert not ring.topics["/tf_static"].entries and ring.topics["/tf_static"].evicted == 1
    held = ring.copy()
    # the window starts before the latched message: it comes back at its own time
    assert [(t, bytes(d[4:])) for t, _, d in held.latched_before(1 * NS)] == [(5 * NS, b"tf")]
    assert held.resent_since(1 * NS) == ["/tf_static"]
    assert ring.topics["/tf_static"].lost_since(1 * NS) == Lost(1, True)


def test_the_size_counts_the_latched_copies() -> None:
    """Big latched messages (maps) and the buffer together stay within --size."""
    limit = 20_000
    ring = RingBuffer(duration_ns=100 * NS, size=limit)
    for i in range(3):  # three latched publishers of 4 kB maps
        conn = ConnInfo("/map", {"callerid": f"/m{i}", "latching": "1"})
        ring.add(ring.topic("/map"), conn, i * NS, [bytes(4000)])
    for i in range(100):
        ring.add(ring.topic("/a"), A, (3 + i) * NS, [bytes(100)])
        assert ring.held <= limit, (i, ring.held)
    assert ring.latched_bytes == 3 * (4000 + ENTRY_OVERHEAD)


def test_what_the_limits_evict_is_counted_by_time_exactly() -> None:
    ring = RingBuffer(duration_ns=100 * NS, size=3 * (8 + ENTRY_OVERHEAD))
    tb = ring.topic("/a")
    for i in range(10):  # two messages a read: runs of two at the same time
        ring.add(tb, A, i * NS, [frame(f"m{i:03}"), frame(f"n{i:03}")])
    assert tb.evicted == 17
    assert tb.lost_since(0) == Lost(17, True)
    assert tb.lost_since(7 * NS) == Lost(3, True)  # m007, n007, m008 (n008 on stays)
    assert ring.topic("/b").lost_since(4 * NS) == Lost(0, True)


def test_past_what_it_remembers_the_count_is_a_least() -> None:
    ring = RingBuffer(duration_ns=100 * NS, size=1 * (8 + ENTRY_OVERHEAD))
    tb = ring.topic("/a")
    for i in range(GONE_KEPT + 10):
        ring.add(tb, A, (i + 1) * NS, [frame(f"m{i:03}")])
    assert tb.lost_since(1 * NS) == Lost(GONE_KEPT, False)
    assert tb.lost_since(20 * NS) == Lost(GONE_KEPT + 9 - 19, True)


def test_messages_evicted_together_are_remembered_as_one_run() -> None:
    """Reads of two messages: 400 evicted in 200 runs are counted exactly, past GONE_KEPT."""
    ring = RingBuffer(duration_ns=1000 * NS, size=2 * (8 + ENTRY_OVERHEAD))
    tb = ring.topic("/a")
    for i in range(201):
        ring.add(tb, A, (i + 1) * NS, [frame(f"m{i:03}"), frame(f"n{i:03}")])
    assert tb.evicted == 400 and GONE_KEPT < 400
    assert tb.lost_since(1 * NS) == Lost(400, True)


def test_a_latched_message_still_buffered_is_written_once() -> None:
    """The buffer gives it in its window; the latched copy is only for what the buffer lost."""
    ring = RingBuffer(duration_ns=100 * NS, size=1 << 30)
    ring.add(ring.topic("/tf_static"), STATIC, 5 * NS, [frame("tf")])
    ring.add(ring.topic("/a"), A, 6 * NS, [frame("m006")])
    held = ring.copy()
    for start in (1 * NS, 5 * NS):  # before it, and exactly at it
        assert held.latched_before(start) == []
        assert held.resent_since(start) == []
    assert [(t, bytes(d[4:])) for t, _, d in held.latched_before(6 * NS)] == [(6 * NS, b"tf")]
    assert texts(held.messages(5 * NS, 6 * NS)) == ["tf", "m006"]


def test_a_latched_topic_counts_its_older_messages_lost() -> None:
    """Only the latched copy comes back: an older message of the same publisher is lost."""
    ring = RingBuffer(duration_ns=100 * NS, size=1 << 30, topic_size=8 + ENTRY_OVERHEAD)
    tb = ring.topic("/tf_static")
    ring.add(tb, STATIC, 1 * NS, [frame("old")])
    ring.add(tb, STATIC, 2 * NS, [frame("new")])  # the topic keeps one: "old" goes
    held = ring.copy()
    assert held.resent_since(1 * NS) == []  # "new" is still buffered
    assert tb.lost_since(1 * NS) == Lost(1, True)


def test_a_window_ending_at_a_message_holds_it() -> None:
    ring = RingBuffer(duration_ns=100 * NS, size=1 << 30)
    ring.add(ring.topic("/a"), A, 5 * NS, [frame("m005")])
    held = ring.copy()
    assert held.any_between(1 * NS, 5 * NS) and held.any_between(5 * NS, 9 * NS)
    assert not held.any_between(1 * NS, 5 * NS - 1) and not held.any_between(5 * NS + 1, 9 * NS)


def test_a_copy_of_some_topics_keeps_their_order_and_their_latched_only() -> None:
    ring = RingBuffer(duration_ns=100 * NS, size=1 << 30)
    c = ConnInfo("/c", {"callerid": "/pc"})
    for i in range(9):
        conn = (A, B, c)[i % 3]
        ring.add(ring.topic(conn.topic), conn, i * NS, [frame(f"m{i:03}")])
    ring.add(ring.topic("/tf_static"), STATIC, 9 * NS, [frame("tf")])
    held = ring.copy({"/a", "/c"})
    assert texts(held.messages(0, 100 * NS)) == ["m000", "m002", "m003", "m005", "m006", "m008"]
    assert held.latched == []
    assert [e[1].topic for e in ring.copy({"/tf_static"}).latched] == ["/tf_static"]


def test_a_latched_publisher_holds_one_copy_in_the_size() -> None:
    ring = RingBuffer(duration_ns=100 * NS, size=1 << 30)
    tb = ring.topic("/tf_static")
    for size in (10, 400, 30, 7):
        ring.add(tb, STATIC, size * NS, [bytes(size)])
    assert ring.latched_bytes == 7 + ENTRY_OVERHEAD
    other = ConnInfo("/tf_static", {"latching": "1"})  # no callerid: a publisher of its own
    ring.add(tb, other, 500 * NS, [bytes(5)])
    assert ring.latched_bytes == 7 + 5 + 2 * ENTRY_OVERHEAD


def test_a_topic_holds_exactly_its_limit() -> None:
    ring = RingBuffer(duration_ns=100 * NS, size=1 << 30, topic_size=3 * (8 + ENTRY_OVERHEAD))
    for i in range(3):
        ring.add(ring.topic("/a"), A, i * NS, [frame(f"m{i:03}")])
    assert ring.topics["/a"].evicted == 0 and ring.topics["/a"].bytes == ring.topic_size


def test_a_cleared_topic_starts_again_from_nothing() -> None:
    """--clear-on-write after the topic limit evicted: the fill, the limits and the order hold."""
    ring = RingBuffer(duration_ns=100 * NS, size=1 << 30, topic_size=4 * (8 + ENTRY_OVERHEAD))
    ring.add(ring.topic("/b"), B, 0, [frame("b000")])
    tb = ring.topic("/a")
    for i in range(1, 7):  # /a keeps 4 of 6; the slots of the two let go wait behind /b's
        ring.add(tb, A, i * NS, [frame(f"m{i:03}")])
    ring.clear({"/a"})
    assert (tb.bytes, len(tb.entries)) == (0, 0)
    ring.size = 4 * (8 + ENTRY_OVERHEAD)
    for i in range(7, 12):
        ring.add(tb, A, i * NS, [frame(f"m{i:03}")])
    assert texts(ring.copy().messages(0, 100 * NS)) == ["m008", "m009", "m010", "m011"]
    assert tb.bytes == ring.bytes == 4 * (8 + ENTRY_OVERHEAD) and len(ring.order) == 4


def test_the_span_of_a_topic() -> None:
    """The live table's span column: seconds from its oldest message to its newest."""
    ring = RingBuffer(duration_ns=100 * NS, size=1 << 30)
    tb = ring.topic("/a")
    assert tb.span() == 0.0
    ring.add(tb, A, 1 * NS, [frame("m001")])
    ring.add(tb, A, 3 * NS + NS // 2, [frame("m003")])
    assert tb.span() == 2.5
    ring.clear()
    assert tb.span() == 0.0
