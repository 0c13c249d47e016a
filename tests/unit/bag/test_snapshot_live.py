"""The live part of snapshots: one queue for every file, each message held once, drops counted."""

from __future__ import annotations

import threading

from rostools.bag.formats.model import ENTRY_OVERHEAD
from rostools.bag.live.ringbuffer import ConnInfo
from rostools.bag.live.snapshot_live import BATCH_BYTES, BATCH_MESSAGES, LiveQueue, LiveReader

NS = 1_000_000_000
A = ConnInfo("/a", {"callerid": "/pa"})
B = ConnInfo("/b", {"callerid": "/pb"})
SIZE = 1000  # bytes a message


def drain(queue: LiveQueue, reader: LiveReader) -> list[int]:
    """What ``reader``'s file writes now: the receive times (s) it takes."""
    got: list[int] = []
    while True:
        batch, done = queue.take(reader, 0)
        queue.written(reader)
        got += [t // NS for t, _, _ in batch]
        if not batch or done:
            return got


def test_four_files_hold_each_message_once() -> None:
    queue = LiveQueue(limit=10 * (SIZE + ENTRY_OVERHEAD))
    readers = [queue.open(None, None) for _ in range(4)]
    for i in range(8):
        queue.push(A, i * NS, [bytes(SIZE)])
    assert queue.bytes == 8 * (SIZE + ENTRY_OVERHEAD)  # not four times that
    assert [r.drops for r in readers] == [0, 0, 0, 0]
    for reader in readers[:3]:
        assert drain(queue, reader) == list(range(8))
    assert len(queue.entries) == 8  # the fourth has not written them yet
    assert drain(queue, readers[3]) == list(range(8))
    assert not queue.entries and queue.bytes == 0


def test_a_file_the_disk_holds_back_counts_every_message_it_lost() -> None:
    queue = LiveQueue(limit=5 * (SIZE + ENTRY_OVERHEAD))
    slow = queue.open(None, None)
    fast = queue.open({"/a"}, 20 * NS)
    for i in range(12):  # /a and /b in turn; the fast file writes as they come
        queue.push(A if i % 2 == 0 else B, i * NS, [bytes(SIZE)])
        drain(queue, fast)
    assert queue.bytes <= queue.limit
    assert slow.drops == 7 and fast.drops == 0  # the slow one kept the last five
    assert drain(queue, slow) == [7, 8, 9, 10, 11]


def test_a_drop_counts_only_what_the_file_wanted() -> None:
    queue = LiveQueue(limit=2 * (SIZE + ENTRY_OVERHEAD))
    only_a = queue.open({"/a"}, 4 * NS)
    for i in range(8):  # /b, and /a past the stop time, are no loss of this file
        queue.push(A if i % 2 == 0 else B, i * NS, [bytes(SIZE)])
    assert only_a.drops == 3  # /a at 0, 2 and 4 s
    queue.end(only_a)
    assert drain(queue, only_a) == [6, 7]  # what it takes; the file writes what it wants
    queue.close(only_a)
    assert not queue.readers and not queue.entries


def test_an_ended_file_takes_what_was_queued_before_its_end() -> None:
    queue = LiveQueue(limit=1 << 20)
    reader = queue.open(None, None)
    queue.push(A, 1 * NS, [bytes(SIZE), bytes(SIZE)])
    queue.end(reader)  # --continue, then ~stop
    queue.push(A, 2 * NS, [bytes(SIZE)])
    assert drain(queue, reader) == [1, 1]
    assert queue.take(reader, 0) == ([], True)


def test_a_file_writing_its_batch_while_the_queue_drops_loses_nothing_it_took() -> None:
    """A fast file and a slow one: the queue drops what the slow one never took, and never
    lets go of a message before every file has taken it."""
    queue = LiveQueue(limit=2 * (SIZE + ENTRY_OVERHEAD))
    writing = queue.open(None, None)
    other = queue.open(None, None)
    queue.push(A, 0, [bytes(SIZE)])
    batch, _ = queue.take(writing, 0)  # being written: m0
    queue.push(A, 1 * NS, [bytes(SIZE)])
    queue.push(A, 2 * NS, [bytes(SIZE)])  # the queue is full: m0 goes
    assert (writing.drops, other.drops) == (0, 1)  # m0 is in the first file's batch
    assert drain(queue, other) == [1, 2]  # the other file writes on: nothing may go yet
    queue.written(writing)
    assert [t for t, _, _ in batch] + [t * NS for t in drain(queue, writing)] == [0, NS, 2 * NS]
    assert writing.drops == 0 and not queue.entries


def test_an_ended_file_counts_as_lost_only_what_came_before_its_end() -> None:
    queue = LiveQueue(limit=1 * (SIZE + ENTRY_OVERHEAD))
    reader = queue.open(None, None)
    queue.push(A, 1 * NS, [bytes(SIZE)])
    queue.push(A, 2 * NS, [bytes(SIZE)])  # m1 dropped: wanted
    queue.end(reader)  # the file ends after m2
    for i in range(3, 6):
        queue.push(A, i * NS, [bytes(SIZE)])  # m2 dropped: wanted; m3, m4: after its end
    assert reader.drops == 2
    assert queue.take(reader, 0) == ([], True)


def test_a_message_bigger_than_the_queue_still_reaches_the_file() -> None:
    """A map larger than --size: the newest message is kept whatever its size."""
    queue = LiveQueue(limit=2 * (SIZE + ENTRY_OVERHEAD))
    reader = queue.open(None, None)
    queue.push(A, 1 * NS, [bytes(SIZE)])
    queue.push(A, 2 * NS, [bytes(10 * SIZE)])
    assert reader.drops == 1 and len(queue.entries) == 1
    queue.push(A, 3 * NS, [bytes(SIZE)])
    assert reader.drops == 2 and len(queue.entries) == 1  # within the limit again
    assert drain(queue, reader) == [3]


def test_a_files_thread_takes_bounded_batches() -> None:
    """At most 1,000 messages or 4 MiB at a time (a message at least), in order."""
    queue = LiveQueue(limit=1 << 30)
    reader = queue.open(None, None)
    queue.push(A, 1 * NS, [bytes(10)] * 2500)
    sizes = []
    while True:
        batch, _ = queue.take(reader, 0)
        if not batch:
            break
        sizes.append(len(batch))
        queue.written(reader)
    assert sizes == [BATCH_MESSAGES, BATCH_MESSAGES, 500]
    mib = 1024 * 1024
    queue.push(B, 2 * NS, [bytes(mib)] * 6 + [bytes(BATCH_BYTES + 1)] * 2)
    sizes = []
    while batch := queue.take(reader, 0)[0]:
        sizes.append(sum(len(d) for _, _, d in batch))
        queue.written(reader)
    assert sizes == [BATCH_BYTES, 2 * mib + BATCH_BYTES + 1, BATCH_BYTES + 1]


def test_a_files_thread_waits_for_messages_rather_than_spinning() -> None:
    queue = LiveQueue(limit=1 << 20)
    reader = queue.open(None, None)
    pushed = threading.Event()

    def push_soon() -> None:
        pushed.wait()
        queue.push(A, 1 * NS, [bytes(SIZE)])

    thread = threading.Thread(target=push_soon)
    thread.start()
    with queue.cond:  # the take below waits: the push can only come once it does
        pushed.set()
        batch, done = queue.take(reader, 30.0)
    thread.join()
    assert [t for t, _, _ in batch] == [1 * NS] and not done


def test_a_file_stopped_while_waiting_takes_nothing_queued_after_its_stop() -> None:
    queue = LiveQueue(limit=1 << 20)
    reader = queue.open(None, None)
    got: list[tuple[list[object], bool]] = []
    waiting = threading.Event()

    def take() -> None:
        with queue.cond:
            waiting.set()
            got.append(queue.take(reader, 30.0))  # type: ignore[arg-type]

    thread = threading.Thread(target=take)
    thread.start()
    waiting.wait()
    with queue.cond:  # held until the thread waits; then ~stop, and a message right after
        queue.end(reader)
        queue.push(A, 1 * NS, [bytes(SIZE)])
    thread.join()
    assert got == [([], True)]


def test_only_live_files_that_want_a_topic_make_it_queued() -> None:
    queue = LiveQueue(limit=1 << 20)
    assert not queue.wanted("/a")
    only_a = queue.open({"/a"}, None)
    assert queue.wanted("/a") and not queue.wanted("/b")
    queue.end(only_a)  # stopped: wants nothing more
    assert not queue.wanted("/a")
    queue.open(None, None)
    assert queue.wanted("/b")
