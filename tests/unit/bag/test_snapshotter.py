"""``bag snapshot``'s recorder without a graph: what it buffers, what a trigger writes, its end."""

from __future__ import annotations

import asyncio
import re
from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

from rostools.bag.formats.model import ENTRY_OVERHEAD
from rostools.bag.live.ringbuffer import Lost
from rostools.bag.live.snapshot import SnapshotOptions, Snapshotter
from rostools.bag.live.snapshot_job import SnapshotJob
from rostools.bag.live.snapshot_srv import NO_DATA_MESSAGE, SnapshotRequest, TriggerError, window
from rostools.errors import UsageError
from tests.unit.bag.test_snapshot_job import PATIENCE, STRING, frame, written

NS = 1_000_000_000
FOREVER = window(0, None, 0.0, forever=True)[1]
#: A file's thread never ends in a traceback, whenever it completes.
pytestmark = pytest.mark.filterwarnings("error::pytest.PytestUnhandledThreadExceptionWarning")


class Clock:
    """ROS time as the test sets it."""

    def __init__(self) -> None:
        self.t_ns = 0

    def now(self) -> int:
        return self.t_ns


class Recorder:
    """A ``Snapshotter`` on a stand-in node, fed frames as its subscribers would feed it."""

    def __init__(self, tmp_path: Path, **options: Any) -> None:
        self.node: Any = SimpleNamespace(resolve=_resolve, subscribers={})
        options.setdefault("min_space", 0)
        options.setdefault("base", tmp_path / "snap.bag")
        opts = SnapshotOptions(topics=["/a", "/b"], **options)
        self.snap = Snapshotter(self.node, opts)
        self.clock = Clock()
        self.snap.clock = self.clock  # type: ignore[assignment]
        self.callbacks = {t: self.snap._on_frames(t) for t in ("/a", "/b")}
        self.conns: dict[str, Any] = {}

    def receive(
        self, topic: str, secs: float, *texts: str, latched: bool = False, typed: bool = True
    ) -> None:
        """Frames of ``topic`` arriving at ``secs`` (from a publisher that is latched or not,
        and that names its type or not)."""
        self.clock.t_ns = round(secs * NS)
        key = f"{topic} {latched} {typed}"
        conn = self.conns.get(key)
        if conn is None:
            header = {**STRING, "callerid": f"/p{topic[1:]}", "topic": topic}
            header["latching"] = "1" if latched else "0"
            if not typed:
                del header["type"]
            conn = self.conns[key] = SimpleNamespace(id=len(self.conns) + 1, header=header)
        self.callbacks[topic]([frame(t) for t in texts], conn, 0.0)

    def trigger(self, secs: float, **request: Any) -> SnapshotJob:
        """A trigger at ``secs``: the job it started."""
        self.clock.t_ns = round(secs * NS)
        if "remote" in request:
            remote = request.pop("remote")
            return self.snap.trigger(SnapshotRequest(**request), remote)
        return self.snap.trigger(SnapshotRequest(**request))  # a service's: remote


def _resolve(name: str) -> str:
    return name if name.startswith("/") else "/" + name


def finished(job: SnapshotJob) -> list[tuple[str, int, str]]:
    job.join(PATIENCE)
    assert not job.is_alive() and job.error is None
    return written(job.path)


def test_frames_are_counted_and_buffered_by_topic(tmp_path: Path) -> None:
    rec = Recorder(tmp_path)
    rec.receive("/a", 1, "a1", "a1b", typed=False)
    assert rec.snap.stats["/a"].type == ""  # not known yet
    rec.receive("/a", 1.5, "a2")
    rec.receive("/b", 2, "b2")
    stats = rec.snap.stats
    assert (stats["/a"].messages, stats["/a"].bytes) == (3, 6 + 7 + 6)
    assert stats["/a"].type == "std_msgs/String"  # from the first publisher that names it
    assert [len(rec.snap.ring.topics[t].entries) for t in ("/a", "/b")] == [3, 1]
    assert rec.snap.ring.topics["/a"].entries[0][0] == 1 * NS  # stamped by the clock


def test_frames_are_counted_and_buffered_by_topic_as_received(tmp_path: Path) -> None:
    rec = Recorder(tmp_path)
    rec.receive("/a", 1, "a1", "a1b")
    rec.receive("/b", 2, "b2")
    stats = rec.snap.stats
    assert (stats["/a"].messages, stats["/a"].bytes) == (2, len(frame("a1")) + len(frame("a1b")))
    assert stats["/a"].type == "std_msgs/String"
    assert [len(rec.snap.ring.topics[t].entries) for t in ("/a", "/b")] == [2, 1]
    assert rec.snap.ring.topics["/a"].entries[0][0] == 1 * NS  # stamped by the clock


def test_a_paused_buffer_counts_but_keeps_nothing_new(tmp_path: Path) -> None:
    rec = Recorder(tmp_path)
    rec.receive("/a", 1, "a1")
    assert rec.snap.set_paused(True) and not rec.snap.set_paused(True)
    rec.receive("/a", 2, "a2")
    assert rec.snap.stats["/a"].messages == 2
    assert len(rec.snap.ring.topics["/a"].entries) == 1
    assert rec.snap.set_paused(False)
    rec.receive("/a", 3, "a3")
    assert len(rec.snap.ring.topics["/a"].entries) == 2


def test_a_trigger_writes_the_whole_buffer_up_to_now(tmp_path: Path) -> None:
    rec = Recorder(tmp_path)
    rec.receive("/a", 1, "a1")
    rec.receive("/b", 2, "b2")
    rec.receive("/a", 3, "a3")
    started: list[SnapshotJob] = []
    rec.snap.on_started = started.append
    job = rec.trigger(4)
    assert started == [job] and rec.snap.jobs == [job]
    assert (job.start_ns, job.until_ns, job.stop_ns) == (1 * NS, 4 * NS, 4 * NS)
    assert finished(job) == [("/a", 1, "a1"), ("/b", 2, "b2"), ("/a", 3, "a3")]
    assert len(rec.snap.ring.topics["/a"].entries) == 2  # the buffer is not cleared


def test_a_trigger_writes_its_window_and_topics(tmp_path: Path) -> None:
    rec = Recorder(tmp_path)
    for i in range(1, 8):
        rec.receive("/a" if i % 2 else "/b", i, f"m{i}")
    job = rec.trigger(8, start_ns=2 * NS, stop_ns=5 * NS, topics=["a", ""])
    assert job.topics == {"/a"}  # resolved as the node resolves names
    assert finished(job) == [("/a", 3, "m3"), ("/a", 5, "m5")]  # not m7, after the window


def test_a_trigger_of_no_message_writes_no_file(tmp_path: Path) -> None:
    rec = Recorder(tmp_path)
    with pytest.raises(TriggerError, match=NO_DATA_MESSAGE):
        rec.trigger(1)  # nothing buffered
    rec.receive("/a", 1, "a1")
    with pytest.raises(TriggerError, match=NO_DATA_MESSAGE):
        rec.trigger(3, start_ns=2 * NS)  # nothing in the window
    with pytest.raises(TriggerError, match=NO_DATA_MESSAGE):
        rec.trigger(3, topics=["/c"])  # a topic not buffered
    rec.receive("/a", 5, "a5")
    with pytest.raises(TriggerError, match=NO_DATA_MESSAGE):
        rec.trigger(6, start_ns=2 * NS, stop_ns=4 * NS)  # a window between messages
    assert not rec.snap.jobs and not list(tmp_path.iterdir())


def test_a_window_ending_later_is_written_as_messages_arrive(tmp_path: Path) -> None:
    """A stop time ahead: the file waits for live messages even with none buffered."""
    rec = Recorder(tmp_path)
    job = rec.trigger(1, stop_ns=3 * NS)
    assert job.live and job.until_ns == 1 * NS
    rec.receive("/a", 2, "a2")
    rec.receive("/b", 3, "b3")
    rec.receive("/a", 4, "a4")  # past the stop time: the file is complete
    assert finished(job) == [("/a", 2, "a2"), ("/b", 3, "b3")]


def test_live_messages_reach_a_file_while_the_buffer_is_paused(tmp_path: Path) -> None:
    rec = Recorder(tmp_path)
    job = rec.trigger(1, stop_ns=FOREVER)
    assert job.stop_ns is None
    rec.snap.set_paused(True)
    rec.receive("/a", 2, "a2")
    assert not rec.snap.ring.topics["/a"].entries
    assert rec.snap.stop_open_ended() == 1
    assert finished(job) == [("/a", 2, "a2")]


def test_at_most_max_writes_files_at_once(tmp_path: Path) -> None:
    rec = Recorder(tmp_path, max_writes=2)
    rec.receive("/a", 1, "a1")
    first = rec.trigger(2, stop_ns=FOREVER)
    timed = rec.trigger(2, stop_ns=50 * NS)  # not open-ended: stop_open_ended leaves it
    with pytest.raises(TriggerError, match=r"2 snapshots are being written.*--max-writes 2"):
        rec.trigger(2)
    assert rec.snap.stop_open_ended() == 1
    assert finished(first) == [("/a", 1, "a1")]
    assert timed.live
    rec.snap._done(first)  # its thread's report, on the event loop
    assert rec.snap.jobs == [timed]
    rec.trigger(3)  # room again
    timed.end()
    assert finished(timed) == [("/a", 1, "a1")]


def test_a_remote_name_is_checked_and_a_local_one_is_not(tmp_path: Path) -> None:
    rec = Recorder(tmp_path)
    rec.receive("/a", 1, "a1")
    with pytest.raises(TriggerError, match="refused the file name"):
        rec.trigger(2, filename="../x.bag")
    (tmp_path / "runs").mkdir()
    job = rec.trigger(2, filename="runs/local.bag", remote=False)  # the API's own name
    assert job.path == tmp_path / "runs" / "local.bag"
    finished(job)


def test_a_full_disk_refuses_the_trigger(tmp_path: Path) -> None:
    rec = Recorder(tmp_path, min_space=1 << 62)
    rec.receive("/a", 1, "a1")
    with pytest.raises(TriggerError, match=r"free on the disk .*: not recording$"):
        rec.trigger(2)
    assert not rec.snap.jobs


def test_clear_on_write_empties_the_topics_written(tmp_path: Path) -> None:
    rec = Recorder(tmp_path, clear_on_write=True)
    rec.receive("/a", 1, "a1")
    rec.receive("/b", 1, "b1")
    job = rec.trigger(2, topics=["/a"])
    assert not rec.snap.ring.topics["/a"].entries and rec.snap.ring.topics["/b"].entries
    assert finished(job) == [("/a", 1, "a1")]  # the file has what was cleared


def test_a_window_counts_what_the_size_evicted_before_the_trigger(tmp_path: Path) -> None:
    rec = Recorder(tmp_path, size=3 * (len(frame("m1")) + ENTRY_OVERHEAD))
    for i in range(1, 7):
        rec.receive("/a", i, f"m{i}")
    whole = rec.trigger(7)  # from the oldest held: nothing of it was lost
    assert whole.evicted == Lost(0, True)
    since = rec.trigger(7, start_ns=2 * NS)  # m2 and m3 were evicted
    assert since.evicted == Lost(2, True) and since.lost == 2
    assert finished(since) == [("/a", 4, "m4"), ("/a", 5, "m5"), ("/a", 6, "m6")]
    rec.receive("/b", 7, "b7")
    other = rec.trigger(7, start_ns=2 * NS, topics=["/b"])  # /b lost nothing
    assert other.evicted == Lost(0, True)
    for job in (whole, other):
        finished(job)


def test_a_window_past_what_the_buffer_remembers_says_at_least(tmp_path: Path) -> None:
    rec = Recorder(tmp_path, topic_size=len(frame("m1")) + ENTRY_OVERHEAD)
    for i in range(1, 400):  # /a keeps one message: 398 evicted, past what is remembered
        rec.receive("/a", i, "m1")
    rec.receive("/b", 400, "b1")
    assert len(rec.snap.ring.topics["/a"].entries) == 1  # --topic-size holds
    job = rec.trigger(401, start_ns=1 * NS)
    assert job.evicted.count < 398 and not job.evicted.exact
    assert job.summary()["lost_exact"] is False
    finished(job)


def test_a_latched_message_the_size_evicted_is_no_loss(tmp_path: Path) -> None:
    rec = Recorder(tmp_path, size=3 * (len(frame("m1")) + ENTRY_OVERHEAD) + 100)
    rec.receive("/b", 1, "map", latched=True)
    for i in range(2, 8):
        rec.receive("/a", i, f"m{i}")
    ring = rec.snap.ring
    assert ring.topics["/b"].evicted == 1 and ring.topics["/a"].evicted > 0
    job = rec.trigger(8, start_ns=1 * NS)
    assert job.evicted == Lost(ring.topics["/a"].evicted, True)  # the map comes from its copy
    assert finished(job)[0] == ("/b", 1, "map")


def test_the_duration_evicts_on_each_tick_unless_paused(tmp_path: Path) -> None:
    rec = Recorder(tmp_path, duration=2.0)
    rec.receive("/a", 1, "a1")
    rec.receive("/a", 2, "a2")
    rec.clock.t_ns = 3 * NS + 1
    rec.snap.set_paused(True)
    rec.snap.tick_limits()
    assert len(rec.snap.ring.topics["/a"].entries) == 2  # a paused buffer holds what it has
    rec.snap.set_paused(False)
    rec.snap.tick_limits()
    assert [e[0] for e in rec.snap.ring.topics["/a"].entries] == [2 * NS]


def test_a_tick_past_the_stop_time_completes_the_file(tmp_path: Path) -> None:
    """No message arrives after the window: the clock alone ends it."""
    rec = Recorder(tmp_path)
    rec.receive("/a", 1, "a1")
    job = rec.trigger(1, stop_ns=3 * NS)
    open_ended = rec.trigger(1, stop_ns=FOREVER)
    rec.clock.t_ns = 3 * NS
    rec.snap.tick_limits()
    assert job.live  # at the stop time a message may still come
    rec.clock.t_ns = 3 * NS + 1
    rec.snap.tick_limits()
    assert not job.live and open_ended.live
    assert finished(job) == [("/a", 1, "a1")]
    open_ended.end()
    finished(open_ended)


def test_each_file_done_is_counted_and_announced_once(tmp_path: Path) -> None:
    rec = Recorder(tmp_path)
    rec.receive("/a", 1, "a1")
    announced: list[SnapshotJob] = []
    told: list[SnapshotJob] = []
    rec.snap.announce = announced.append
    rec.snap.on_written = told.append
    good = rec.trigger(2)
    finished(good)
    lossy = rec.trigger(2)
    finished(lossy)
    lossy.evicted = Lost(1, True)
    for job in (good, lossy, good):
        rec.snap._done(job)
    assert announced == told == [good, lossy]
    assert list(rec.snap.finished) == [good, lossy] and not rec.snap.jobs
    assert (rec.snap.failed, rec.snap.lossy) == (0, 1)
    for _ in range(2):
        failed = rec.trigger(2)
        failed.join(PATIENCE)
        failed.error = OSError("disk gone")
        failed.evicted = Lost(1, True)  # a failed file counts as failed, not lossy
        rec.snap._done(failed)
    assert (rec.snap.failed, rec.snap.lossy) == (2, 1)


def test_the_recorder_remembers_the_last_thousand_files(tmp_path: Path) -> None:
    """A recorder left running for days: the summary at its end lists the latest files."""
    rec = Recorder(tmp_path)
    jobs: list[Any] = [SimpleNamespace(error=None, lost=0) for _ in range(1001)]
    for job in jobs:
        rec.snap.jobs.append(job)
        rec.snap._done(job)
    assert list(rec.snap.finished) == jobs[1:]


def test_the_end_completes_every_file_and_reports_it(tmp_path: Path) -> None:
    rec = Recorder(tmp_path)
    rec.receive("/a", 1, "a1")
    told: list[SnapshotJob] = []
    rec.snap.on_written = told.append

    async def run() -> SnapshotJob:
        rec.snap._loop = asyncio.get_running_loop()
        job = rec.trigger(2, stop_ns=FOREVER)
        rec.receive("/a", 3, "a3")
        await rec.snap._end()
        return job

    job = asyncio.run(run())
    assert told == [job] and not rec.snap.jobs and rec.snap.closing
    assert finished(job) == [("/a", 1, "a1"), ("/a", 3, "a3")]
    rec.receive("/a", 4, "a4")  # closing: nothing more is buffered
    assert [e[0] for e in rec.snap.ring.topics["/a"].entries] == [1 * NS, 3 * NS]


def test_the_end_reports_a_file_whose_report_could_not_reach_the_loop(tmp_path: Path) -> None:
    """Triggered before the run had its event loop (a signal at start-up)."""
    rec = Recorder(tmp_path)
    rec.receive("/a", 1, "a1")
    told: list[SnapshotJob] = []
    rec.snap.on_written = told.append
    job = rec.trigger(2)
    job.join(PATIENCE)
    assert rec.snap.jobs == [job] and not told
    asyncio.run(rec.snap._end())
    assert told == [job] and not rec.snap.jobs


def test_a_file_done_as_the_loop_closes_ends_quietly(tmp_path: Path) -> None:
    class Closing:
        def is_closed(self) -> bool:
            return False

        def call_soon_threadsafe(self, *_: object) -> None:
            raise RuntimeError("Event loop is closed")

    rec = Recorder(tmp_path)
    rec.receive("/a", 1, "a1")
    rec.snap._loop = Closing()  # type: ignore[assignment]
    job = rec.trigger(2)
    assert finished(job) == [("/a", 1, "a1")]
    assert rec.snap.jobs == [job]  # the end reports it


def test_other_topics_do_not_crowd_a_live_file_out_of_the_queue(tmp_path: Path) -> None:
    """A live file of /a, a flood on /b: the queue (--size) holds only what a file wants."""
    rec = Recorder(tmp_path, size=3 * (len(frame("a2")) + ENTRY_OVERHEAD))
    rec.receive("/a", 1, "a1")
    live = rec.trigger(1, stop_ns=FOREVER, topics=["/a"])
    for i in range(20):
        rec.receive("/b", 2, f"b{i % 10}")
    rec.receive("/a", 3, "a3")
    assert not any(e[1].topic == "/b" for e in rec.snap.live.entries)
    live.end()
    assert finished(live) == [("/a", 1, "a1"), ("/a", 3, "a3")] and live.drops == 0


def test_a_file_done_is_reported_on_the_event_loop(tmp_path: Path) -> None:
    rec = Recorder(tmp_path)
    rec.receive("/a", 1, "a1")

    async def run() -> list[SnapshotJob]:
        loop = asyncio.get_running_loop()
        rec.snap._loop = loop
        told = loop.create_future()
        rec.snap.on_written = told.set_result
        job = rec.trigger(2)
        return [await asyncio.wait_for(told, PATIENCE), job]

    reported, job = asyncio.run(run())
    assert reported is job and list(rec.snap.finished) == [job]


def test_a_new_publisher_of_a_topic_is_kept_with_its_own_header(tmp_path: Path) -> None:
    rec = Recorder(tmp_path)
    rec.receive("/a", 1, "a1")
    rec.receive("/a", 2, "map", latched=True)  # another publisher, latched
    headers = [e[1].header.get("latching") for e in rec.snap.ring.topics["/a"].entries]
    assert headers == ["0", "1"]
    assert len(rec.snap.ring.latched) == 1


LIMITS = "the snapshot's duration, size and --max-writes must be positive"
WINDOW = "--before must be positive and --after not negative"


@pytest.mark.parametrize(
    ("options", "why"),
    [
        ({"duration": 0.0}, LIMITS),
        ({"size": 0}, LIMITS),
        ({"topic_size": -1}, LIMITS),
        ({"max_writes": 0}, LIMITS),
        ({"before": 0.0}, WINDOW),
        ({"after": -1.0}, WINDOW),
    ],
)
def test_limits_that_cannot_be_met_are_usage_errors(tmp_path: Path, options: Any, why: str) -> None:
    with pytest.raises(UsageError) as refused:
        Recorder(tmp_path, **options)
    assert str(refused.value) == why


def test_the_smallest_limits_are_taken(tmp_path: Path) -> None:
    rec = Recorder(tmp_path, duration=0.001, size=1, topic_size=0, max_writes=1, before=0.001)
    assert rec.snap.opts.after == 0.0


@pytest.mark.parametrize(
    ("options", "requested", "name", "compression"),
    [
        ({"prefix": "crash"}, "", r"crash_\d{4}(-\d\d){5}\.bag", None),
        ({}, "", r"\d{4}(-\d\d){5}\.bag", None),
        ({"format": "mcap"}, "", r"\d{4}(-\d\d){5}\.mcap", None),
        ({"compression": "lz4"}, "given.bag", r"given\.bag", "lz4"),
        ({"compression": "bz2"}, "given.mcap", r"given\.mcap", None),  # MCAP has no bz2
        ({"chunk_size": 1024}, "", r".*\.bag", None),
    ],
)
def test_file_names_and_formats(
    tmp_path: Path, options: dict[str, Any], requested: str, name: str, compression: str | None
) -> None:
    rec = Recorder(tmp_path, **options)
    spec = rec.snap._file_spec(requested)
    assert spec.path.parent == tmp_path
    assert re.fullmatch(name, spec.path.name), spec.path.name
    assert spec.format == spec.path.suffix[1:]
    assert spec.compression == compression
    assert spec.chunk_size == options.get("chunk_size")


def test_a_name_being_written_is_not_given_twice(tmp_path: Path) -> None:
    rec = Recorder(tmp_path, name="run.bag")
    rec.receive("/a", 1, "a1")
    first = rec.trigger(2, stop_ns=FOREVER)
    second = rec.trigger(2)
    assert (first.path.name, second.path.name) == ("run.bag", "run_1.bag")
    first.end()
    for job in (first, second):
        finished(job)
