"""The live part of snapshots: one queue for every file, each message held once, drops counted."""

from __future__ import annotations

from rostools.bag.recorder import ENTRY_OVERHEAD
from rostools.bag.ringbuffer import ConnInfo
from rostools.bag.snapshot_live import LiveQueue, LiveReader

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
