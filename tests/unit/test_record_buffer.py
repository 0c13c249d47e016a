"""``bag record -b`` bounds the memory the process holds for messages, not only their bytes."""

from __future__ import annotations

import threading
import time
import tracemalloc
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

from rostools.bag.formats.model import ENTRY_OVERHEAD
from rostools.bag.live import recorder

BUFFER = 1024 * 1024
HEADER = {"topic": "/t", "type": "std_msgs/String", "md5sum": "992ce8a1687cec8c8bd883ec73ca41d1"}


def _recorder(tmp_path: Path) -> recorder.Recorder:
    node: Any = SimpleNamespace(resolve=lambda name: name)
    opts = recorder.RecordOptions(topics=["/t"], base=tmp_path / "x.bag", buffer_bytes=BUFFER)
    return recorder.Recorder(node, opts)


def _flood(rec: recorder.Recorder, messages: int) -> None:
    """What 100 topics of 16-byte strings deliver: many small frames, in reads of 500."""
    on_frames = rec._on_frames("/t")
    conn: Any = SimpleNamespace(id=1, header=HEADER)
    for _ in range(messages // 500):
        on_frames([bytes(16) for _ in range(500)], conn, 0.0)  # 500 distinct objects


def test_small_messages_count_their_overhead(tmp_path: Path) -> None:
    rec = _recorder(tmp_path)  # the writer never runs: everything stays queued
    tracemalloc.start()
    try:
        _flood(rec, 200_000)
        held, _ = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    # Counting the payload alone held 65,536 messages, 10 MB, for a 1 MB buffer.
    assert held < 1.25 * BUFFER, held
    assert rec.drops > 190_000


def test_a_batch_being_written_counts_too(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    rec = _recorder(tmp_path)
    taken, release = threading.Event(), threading.Event()
    write = recorder._Writer._write

    def slow_disk(self: recorder._Writer, batch: Any) -> None:
        taken.set()
        release.wait(30)
        write(self, batch)

    monkeypatch.setattr(recorder._Writer, "_write", slow_disk)
    rec._writer.start()
    try:
        _flood(rec, 20_000)  # fills the buffer
        assert taken.wait(10)
        _flood(rec, 20_000)  # while the writer is stuck on the first batch
        # Resetting the count when the writer took its batch let the queue fill again: 2x.
        assert rec.queued_bytes + rec.writing_bytes <= BUFFER + 500 * ENTRY_OVERHEAD
        held = sum(len(e[4]) + ENTRY_OVERHEAD for e in rec.queue)
        assert held == rec.queued_bytes  # how much the writer took depends on when it woke
    finally:
        release.set()
        with rec.cond:
            rec.closing = True
            rec.cond.notify()
        rec._writer.join(30)
    assert not rec._writer.is_alive() and rec._writer.error is None
    deadline = time.monotonic() + 5
    while rec.writing_bytes and time.monotonic() < deadline:
        time.sleep(0.01)
    assert rec.writing_bytes == 0
