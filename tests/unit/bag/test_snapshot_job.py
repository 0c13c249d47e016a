"""One snapshot file, written by its own thread: the window's buffered part, then its live part."""

from __future__ import annotations

import threading
import time
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

from rostools.bag.formats.access import bag_info, detect_format
from rostools.bag.formats.model import ENTRY_OVERHEAD
from rostools.bag.live import snapshot_job
from rostools.bag.live.bagfile import active_name
from rostools.bag.live.ringbuffer import ConnInfo, Held, Lost, RingBuffer
from rostools.bag.live.snapshot_job import FileSpec, SnapshotJob, wait_joined
from rostools.bag.live.snapshot_live import LiveQueue
from tests.support.bagdata import read_stream

NS = 1_000_000_000
STRING = {"type": "std_msgs/String", "md5sum": "992ce8a1687cec8c8bd883ec73ca41d1"}
A = ConnInfo("/a", {**STRING, "callerid": "/pa", "message_definition": "string data\n"})
B = ConnInfo("/b", {**STRING, "callerid": "/pb", "message_definition": "string data\n"})
STATIC = ConnInfo(
    "/static", {**STRING, "callerid": "/ps", "latching": "1", "message_definition": "string data\n"}
)
#: Long enough for a thread on a loaded machine; the tests wait on events, not on this.
PATIENCE = 30.0
#: A file's thread never ends in a traceback.
pytestmark = pytest.mark.filterwarnings("error::pytest.PytestUnhandledThreadExceptionWarning")


def frame(text: str) -> bytes:
    """A std_msgs/String of ``text``."""
    return len(text).to_bytes(4, "little") + text.encode()


def buffered(*messages: tuple[ConnInfo, int, str]) -> RingBuffer:
    """A buffer holding (connection, seconds, text) messages, in that order."""
    ring = RingBuffer(duration_ns=1000 * NS, size=1 << 30)
    for conn, secs, text in messages:
        ring.add(ring.topic(conn.topic), conn, secs * NS, [frame(text)])
    return ring


class Done:
    """``on_done``: the jobs it was called with, and an event once it was."""

    def __init__(self) -> None:
        self.jobs: list[SnapshotJob] = []
        self.event = threading.Event()

    def __call__(self, job: SnapshotJob) -> None:
        self.jobs.append(job)
        self.event.set()


def job_of(
    path: Path | FileSpec,
    held: Held,
    window: tuple[int, int, int | None],
    live: LiveQueue | None = None,
    topics: set[str] | None = None,
    evicted: Lost | None = None,
) -> tuple[SnapshotJob, Done]:
    """A job writing ``held``'s [start, until], then live messages up to stop (None: end())."""
    start, until, stop = window
    done = Done()
    job = SnapshotJob(
        path if isinstance(path, FileSpec) else FileSpec(path, "bag", None, None),
        held,
        start,
        until,
        stop,
        topics,
        live if live is not None else LiveQueue(1 << 20),
        done,
        evicted,
    )
    return job, done


def written(path: Path) -> list[tuple[str, int, str]]:
    """(topic, seconds, text) of each message in the file, in time order."""
    return [(topic, t // NS, bytes(d[4:]).decode()) for topic, _, t, d in read_stream(path)]


def test_the_window_of_the_buffer_is_written_and_named_once_complete(tmp_path: Path) -> None:
    ring = buffered((A, 1, "a1"), (B, 2, "b2"), (A, 3, "a3"), (B, 4, "b4"), (A, 5, "a5"))
    path = tmp_path / "snap.bag"
    job, done = job_of(path, ring.copy(), (2 * NS, 4 * NS, 4 * NS))
    assert not job.live  # the window ends at the trigger: nothing live to wait for
    job.start()
    job.join(PATIENCE)
    assert done.jobs == [job] and job.error is None
    assert written(path) == [("/b", 2, "b2"), ("/a", 3, "a3"), ("/b", 4, "b4")]
    assert not (tmp_path / "snap.bag.active").exists()
    summary = job.summary()
    assert summary["name"] == str(path)
    assert (summary["messages"], summary["bytes"]) == (3, 3 * len(frame("a3")))
    assert (summary["start"], summary["end"], summary["duration"]) == (2.0, 4.0, 2.0)
    assert summary["window_ns"] == [2 * NS, 4 * NS]
    assert (summary["lost"], summary["evicted"], summary["drops"]) == (0, 0, 0)
    assert summary["lost_exact"] is True and summary["error"] is None
    assert 0 <= summary["seconds"] < PATIENCE
    assert job.done == job.total == 3 * len(frame("a3"))  # the progress of the buffered part


def test_a_latched_message_older_than_the_window_opens_the_file(tmp_path: Path) -> None:
    ring = buffered((STATIC, 1, "map"), (A, 5, "a5"), (A, 6, "a6"))
    job, _ = job_of(tmp_path / "snap.bag", ring.copy(), (5 * NS, 6 * NS, 6 * NS))
    job.start()
    job.join(PATIENCE)
    assert written(job.path) == [("/static", 5, "map"), ("/a", 5, "a5"), ("/a", 6, "a6")]


def test_the_live_part_goes_on_to_the_stop_time(tmp_path: Path) -> None:
    """--after: what arrives after the trigger, up to the stop time, then the file is complete."""
    ring = buffered((A, 1, "a1"), (A, 2, "a2"))
    live = LiveQueue(1 << 20)
    job, done = job_of(tmp_path / "snap.bag", ring.copy(), (0, 2 * NS, 4 * NS), live)
    assert job.live
    job.start()
    live.push(A, 3 * NS, [frame("a3")])
    live.push(B, 4 * NS, [frame("b4")])
    assert not done.event.wait(0.2)  # the stop time has not been passed
    live.push(A, 5 * NS, [frame("a5")])  # past the stop time: the file is complete
    assert done.event.wait(PATIENCE)
    job.join(PATIENCE)
    assert written(job.path) == [
        ("/a", 1, "a1"),
        ("/a", 2, "a2"),
        ("/a", 3, "a3"),
        ("/b", 4, "b4"),
    ]
    assert not job.live and not live.readers and not live.entries  # the queue let go


def test_an_open_ended_file_writes_its_topics_until_ended(tmp_path: Path) -> None:
    """--continue on /a: live messages until stopped, other topics left out."""
    live = LiveQueue(1 << 20)
    job, done = job_of(tmp_path / "snap.bag", Held([], {}), (0, 1 * NS, None), live, {"/a"})
    assert job.live and job.wants("/a") and not job.wants("/b")
    job.start()
    for i in range(2, 6):
        live.push(A if i % 2 else B, i * NS, [frame(f"m{i}")])
    assert not done.event.wait(0.2)
    job.end()
    assert done.event.wait(PATIENCE)
    assert written(job.path) == [("/a", 3, "m3"), ("/a", 5, "m5")]
    assert job.total == 1  # an empty buffered part is complete at once
    assert job.summary()["window_ns"] == [0, None]


def test_what_the_window_lost_is_counted_and_told(tmp_path: Path) -> None:
    """Evicted before the trigger (at least 3), and live messages the full queue let go."""
    live = LiveQueue(2 * (len(frame("m0")) + ENTRY_OVERHEAD))
    job, done = job_of(
        tmp_path / "snap.bag", Held([], {}), (0, 0, 100 * NS), live, None, Lost(3, False)
    )
    for i in range(5):  # before the thread takes any: the queue keeps the last two
        live.push(A, (i + 1) * NS, [frame(f"m{i}")])
    assert job.drops == 3
    job.start()
    job.end()
    assert done.event.wait(PATIENCE)
    summary = job.summary()
    assert (job.lost, summary["lost"], summary["evicted"], summary["drops"]) == (6, 6, 3, 3)
    assert summary["lost_exact"] is False
    assert [text for _, _, text in written(job.path)] == ["m3", "m4"]


def test_a_file_that_cannot_be_written_is_reported_and_lets_go(tmp_path: Path) -> None:
    live = LiveQueue(1 << 20)
    path = tmp_path / "no such folder" / "snap.bag"
    job, done = job_of(path, buffered((A, 1, "a1")).copy(), (0, 1 * NS, None), live)
    job.start()
    assert done.event.wait(PATIENCE)
    summary = job.summary()
    assert summary["error"] and "no such folder" in summary["error"]
    assert (summary["messages"], summary["bytes"], summary["start"]) == (0, 0, None)
    assert summary["duration"] == 0.0
    assert not job.live and not live.readers and not live.wanted("/a")  # nothing held for it


def test_the_summary_outlives_the_files_index(tmp_path: Path) -> None:
    """The recorder keeps finished jobs: their summary is kept, their writer is not."""
    job, _ = job_of(tmp_path / "snap.bag", buffered((A, 1, "a1")).copy(), (0, 1 * NS, 1 * NS))
    assert job.summary()["messages"] == 0  # not started yet
    job.start()
    job.join(PATIENCE)
    assert job.file is None
    assert job.summary()["messages"] == 1 and job.summary()["start"] == 1.0


def test_wait_joined_shares_one_deadline() -> None:
    """Files still being written when the recorder ends cost the timeout once, not each."""
    release = threading.Event()
    slow = [threading.Thread(target=release.wait, daemon=True) for _ in range(3)]
    for thread in slow:
        thread.start()
    began = time.monotonic()
    wait_joined(slow, 0.3)  # type: ignore[arg-type]
    waited = time.monotonic() - began
    release.set()
    assert 0.3 <= waited < 0.3 * 3
    for thread in slow:
        thread.join(PATIENCE)
    began = time.monotonic()
    wait_joined(slow, PATIENCE)  # type: ignore[arg-type]
    assert time.monotonic() - began < PATIENCE  # done threads return at once


@pytest.mark.parametrize("stop", [1 * NS, 2 * NS])
def test_a_stop_time_not_after_the_trigger_writes_no_live_part(tmp_path: Path, stop: int) -> None:
    live = LiveQueue(1 << 20)
    job, done = job_of(
        tmp_path / "snap.bag", buffered((A, 1, "a1")).copy(), (0, 2 * NS, stop), live
    )
    assert not job.live
    live.push(A, 2 * NS, [frame("after")])  # arrives after the trigger: not in this file
    job.start()
    assert done.event.wait(PATIENCE)
    assert [text for _, _, text in written(job.path)] == ["a1"]


def test_a_file_whose_window_ended_completes_when_the_queue_drops_past_its_end(
    tmp_path: Path,
) -> None:
    """A slow disk: the window ends, and another file keeps the full queue moving past it."""
    size = len(frame("m1")) + ENTRY_OVERHEAD
    live = LiveQueue(1 * size)
    job, done = job_of(tmp_path / "snap.bag", Held([], {}), (0, 0, 3 * NS), live)
    other = live.open(None, None)  # an open-ended file, writing as messages come
    for i in range(1, 4):
        live.push(A, i * NS, [frame(f"m{i}")])
    job.end()  # the clock passed the stop time (tick_limits)
    for i in range(4, 7):
        live.push(A, i * NS, [frame(f"m{i}")])
        live.take(other, 0)
        live.written(other)
    job.start()
    assert done.event.wait(PATIENCE)
    summary = job.summary()
    assert summary["error"] is None and job.path.exists()
    assert summary["drops"] == 3 and summary["messages"] == 0  # m1, m2, m3: the disk was slow


def test_latched_messages_of_several_topics_keep_their_topics(tmp_path: Path) -> None:
    other = ConnInfo("/map", {**STATIC.header, "callerid": "/pm"})
    ring = buffered((STATIC, 1, "tf"), (other, 2, "map"), (A, 5, "a5"))
    job, _ = job_of(tmp_path / "snap.bag", ring.copy(), (5 * NS, 5 * NS, 5 * NS))
    job.start()
    job.join(PATIENCE)
    assert sorted(written(job.path)) == [("/a", 5, "a5"), ("/map", 5, "map"), ("/static", 5, "tf")]


def test_under_sim_time_a_message_at_the_stop_time_of_another_topic_ends_nothing(
    tmp_path: Path,
) -> None:
    """/clock gives many messages one time: those of the file's topic at the stop time count."""
    live = LiveQueue(1 << 20)
    job, done = job_of(tmp_path / "snap.bag", Held([], {}), (0, 1 * NS, 3 * NS), live, {"/a"})
    job.start()
    live.push(B, 3 * NS, [frame("b3")])
    deadline = time.monotonic() + PATIENCE
    while job.reader.pos < 1 and time.monotonic() < deadline:  # the thread has written b3
        time.sleep(0.001)
    live.push(A, 3 * NS, [frame("a3")])
    live.push(A, 4 * NS, [frame("a4")])
    assert done.event.wait(PATIENCE)
    assert written(job.path) == [("/a", 3, "a3")]


def test_an_idle_file_is_handed_to_the_os(tmp_path: Path) -> None:
    """A live file with nothing new still reaches the disk (a crash loses at most a second)."""
    live = LiveQueue(1 << 20)
    job, done = job_of(tmp_path / "snap.bag", Held([], {}), (0, 0, None), live)
    job.start()
    live.push(A, 1 * NS, [frame("x" * 5000)])
    active = active_name(job.path)
    deadline = time.monotonic() + PATIENCE
    while time.monotonic() < deadline and (not active.exists() or active.stat().st_size < 5000):
        time.sleep(0.05)
    assert active.stat().st_size >= 5000
    job.end()
    assert done.event.wait(PATIENCE)


@pytest.mark.parametrize(
    ("kind", "compression", "stored"),
    [("bag", "lz4", "lz4"), ("bag", None, "none"), ("mcap", "lz4", "lz4"), ("mcap", None, "zstd")],
)
def test_a_file_is_written_as_asked(
    tmp_path: Path, kind: str, compression: str | None, stored: str
) -> None:
    ring = buffered(*[(A, i, "x" * 300) for i in range(1, 40)])
    spec = FileSpec(tmp_path / f"snap.{kind}", kind, compression, 2048)
    job, _ = job_of(spec, ring.copy(), (0, 40 * NS, 40 * NS))
    job.start()
    job.join(PATIENCE)
    assert detect_format(job.path) == kind
    info = bag_info(job.path)
    assert info.message_count == 39 and info.chunk_count > 2  # chunks of about 2 kB
    assert [c.compression for c in info.compression] == [stored]


def test_the_progress_counts_the_bytes_written(tmp_path: Path) -> None:
    """The live table's "writing NAME: N% of the buffered part"."""
    ring = buffered((A, 1, "a" * 10), (A, 2, "b" * 20), (A, 3, "c" * 30))
    job, _ = job_of(tmp_path / "snap.bag", ring.copy(), (0, 3 * NS, 3 * NS))
    assert (job.done, job.total) == (0, 0)  # not known yet
    seen: list[tuple[int, int]] = []
    out: Any = SimpleNamespace(
        write=lambda *_: seen.append((job.done, job.total)), flush_if_due=lambda: None
    )
    job._write_held(out)
    sizes = [14, 24, 34]
    assert seen == [(0, 72), (14, 72), (38, 72)] and sum(sizes) == 72
    assert job.done == job.total == 72


def test_seconds_is_the_time_from_the_trigger_to_the_millisecond(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    clock = SimpleNamespace(t=1000.0)
    monkeypatch.setattr(snapshot_job, "time", SimpleNamespace(monotonic=lambda: clock.t))
    job, _ = job_of(tmp_path / "snap.bag", Held([], {}), (0, 0, 0))
    clock.t = 1001.23456
    assert job.summary()["seconds"] == 1.235


def test_a_files_thread_is_named_after_it_and_does_not_hold_the_process(tmp_path: Path) -> None:
    """Thread dumps name the file; a file stuck on a dead disk cannot keep the process alive."""
    job, _ = job_of(tmp_path / "snap.bag", Held([], {}), (0, 0, 0))
    assert job.name == "rostools-snapshot-snap.bag" and job.daemon
