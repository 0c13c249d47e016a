"""``bag snapshot`` beside ``bag record``, in the same runs, on one rosmaster.

``snapshot_buffering``: one roscpp ``multi_pub`` offers TOPICS topics at RATE Hz each (SIZE-byte
std_msgs/String) for DURATION s (``ROSTOOLS_BENCH_SNAPSHOT_SECONDS``, default 60) to
``bag snapshot -a --size 256`` and ``bag record -a`` at once. Reported: each one's CPU per
message received (from when both are subscribed to when the publisher is done), and the
snapshot's peak resident memory against its 256 MB limit: the fixed overhead is the peak less
the limit (VmRSS/VmHWM sampled every 0.1 s; its idle size once subscribed is in the note).

``snapshot_write_1g``: a roscpp ``pub_rate`` offers 1 MB images at 50 Hz and ``multi_pub`` a
small topic at 1 kHz, to both recorders. Once the buffer holds more than 1 GB of images,
``bag trigger --topics /snap_img --before`` writes 1 GB of them; the time from the call to
the complete file is reported beside what this machine writes into its page cache. The
small topic goes on all the while: what the snapshot's buffer and ``bag record``'s file hold
of it, against what was published, is what each lost live (goal 0).

``snapshot_four_writes``: a roscpp ``pub_rate`` floods 1 MB images at 70 Hz (70 MB/s) into
``bag snapshot --size 40`` and, beside it, the real ``rosbag record``. Four ``bag trigger
--before 0.3 --after 3`` start 0.5 s apart, so four files are written at once. Reported: the
messages of the four windows lost (goal 0; the recorder's exact count, cross-checked against
the images rosbag record got, by their stamps), beside what ``rosbag record`` lost of the same
flood; and the snapshot's peak RSS against the bound of docs/bag.md: idle + --size x
(2 + files) + 4 MB a file.

Every process is stopped through its PID; files go to benchmarks/build/snapshot/ (gitignored)
and are deleted once counted.
"""

from __future__ import annotations

import json
import os
import subprocess
import time
from pathlib import Path

from benchmarks.bench_bag_live import _finish, _page_cache_mb_s
from benchmarks.bench_load import _PeakRss
from benchmarks.bench_load_memory import _wait_subscribed
from benchmarks.common import (
    ROOT,
    Result,
    cpp_peer,
    cpu_seconds,
    master,
    ros_env,
    rostools_cmd,
    start,
    status_kb,
    stop,
)

BUILD = ROOT / "benchmarks" / "build" / "snapshot"
PEERS = Path(__file__).with_name("peers")
DURATION = float(os.environ.get("ROSTOOLS_BENCH_SNAPSHOT_SECONDS", "60"))
TOPICS, RATE, SIZE = 100, 1000.0, 100
LIMIT_MB = 256
PREFIX = "/snap_load_"
CLOSE_TIMEOUT = 120.0
IMAGE = 1_000_000  # bytes a message
IMAGE_RATE = 50.0
WRITE_BYTES = 1_000_000_000  # the snapshot written


def _recorders() -> dict[str, list[str]]:
    ours = rostools_cmd()
    return {
        "snapshot": [*ours, "bag", "snapshot", "-a", "-F", "json", "-L", "0", "--size",
                     str(LIMIT_MB), "-d", "600", "__name:=bench_snap"],
        "record": [*ours, "bag", "record", "-a", "-q", "-L", "0", "-O", "record.bag"],
    }  # fmt: skip


Procs = dict[str, subprocess.Popen[bytes]]


def _start_all(
    env: dict[str, str], recorders: dict[str, list[str]]
) -> tuple[Procs, dict[str, _PeakRss]]:
    """Start each recorder, its output in BUILD/LABEL.out, and a sampler of its memory."""
    BUILD.mkdir(parents=True, exist_ok=True)
    for old in BUILD.glob("*.bag*"):
        old.unlink()
    procs, samplers = {}, {}
    for label, argv in recorders.items():
        out = (BUILD / f"{label}.out").open("wb")
        procs[label] = start(argv, env, stdout=out, stderr=subprocess.STDOUT, cwd=BUILD)
        out.close()
        samplers[label] = _PeakRss(procs[label].pid)
        samplers[label].start()
    return procs, samplers


def _stop_all(procs: Procs, samplers: dict[str, _PeakRss]) -> dict[str, int]:
    """Stop each recorder (SIGINT, its file closed); each one's peak memory in kB."""
    for proc in procs.values():
        _finish(proc, CLOSE_TIMEOUT)
    return {label: sampler.stop() for label, sampler in samplers.items()}


def _last_event(label: str) -> dict[str, object]:
    lines = [ln for ln in (BUILD / f"{label}.out").read_text().splitlines() if ln.startswith("{")]
    return json.loads(lines[-1]) if lines else {}


def _truth(out: bytes) -> dict[str, float]:
    """The publisher's own count, its last JSON line."""
    truth: dict[str, float] = json.loads(
        [ln for ln in out.decode().splitlines() if ln.startswith("{")][-1]
    )
    return truth


def bench_snapshot_buffering() -> list[Result]:
    """100 topics x 1 kHz: CPU per message beside bag record; peak RSS against the limit."""
    publisher = [cpp_peer("multi_pub", PEERS), PREFIX, str(TOPICS), str(SIZE), str(RATE),
                 str(DURATION), "--wait-subscribers", "2", "--linger", "2"]  # fmt: skip
    with master() as uri:
        env = ros_env(uri)
        procs, samplers = _start_all(env, _recorders())
        try:
            pub = start(publisher, env, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
            try:
                _wait_subscribed(uri, procs, PREFIX, TOPICS)
                cpu0 = {label: cpu_seconds(p.pid) for label, p in procs.items()}
                idle = {label: status_kb(p.pid) for label, p in procs.items()}
                pub_out, _ = pub.communicate(timeout=DURATION + 300)
                cpu = {label: cpu_seconds(p.pid) - cpu0[label] for label, p in procs.items()}
            finally:
                stop(pub)
        finally:
            peaks = _stop_all(procs, samplers)
    truth = _truth(pub_out)
    snap = _last_event("snapshot")
    recorded = _count(BUILD / "record.bag", PREFIX)
    received = int(snap.get("received", 0))  # type: ignore[call-overload]
    per_msg = {
        "snapshot": 1e6 * cpu["snapshot"] / max(received, 1),
        "record": 1e6 * cpu["record"] / max(recorded, 1),
    }
    overhead_mb = peaks["snapshot"] / 1024 - LIMIT_MB
    setup = (
        f"{TOPICS} topics x {RATE:g} Hz, {SIZE}-byte std_msgs/String, {DURATION:g} s, one roscpp "
        f"multi_pub into both at once; published {int(truth['published']):,} "
        f"({truth['rate']:,.0f} msg/s); snapshot received {received:,}, evicted "
        f"{int(snap.get('evicted', 0)):,}; record wrote {recorded:,}"  # type: ignore[call-overload]
    )
    return [
        Result(
            "snapshot vs record: CPU per message (100 topics x 1 kHz)", "us/msg",
            per_msg["snapshot"], per_msg["record"], "<= 1x bag record",
            per_msg["snapshot"] <= per_msg["record"],
            f"{setup}; CPU from both subscribed to the publisher's end; 'ROS 1' is bag record",
        ),
        Result(
            f"snapshot peak RSS, --size {LIMIT_MB} (100 topics x 1 kHz)", "MB",
            peaks["snapshot"] / 1024, peaks["record"] / 1024,
            f"<= {LIMIT_MB} MB + fixed overhead", None,
            f"{setup}; fixed overhead = peak - limit = {overhead_mb:.0f} MB (idle once "
            f"subscribed: {idle['snapshot'] / 1024:.0f} MB); 'ROS 1' is bag record -b 256's peak",
        ),
    ]  # fmt: skip


def _count(path: Path, prefix: str) -> int:
    from rostools.bag.formats.access import bag_info

    if not path.exists():
        return 0
    count = sum(t.messages for t in bag_info(path).topics if t.topic.startswith(prefix))
    path.unlink()
    return count


def _trigger(env: dict[str, str], *args: str) -> tuple[float, dict[str, object]]:
    began = time.monotonic()
    done = subprocess.run(
        [*rostools_cmd(), "bag", "trigger", "/bench_snap", "-F", "json", *args],
        env=env, capture_output=True, timeout=600, check=False, cwd=BUILD,
    )  # fmt: skip
    if done.returncode != 0:
        raise RuntimeError(f"bag trigger failed: {done.stderr.decode()[-500:]}")
    return time.monotonic() - began, json.loads(done.stdout)


def bench_snapshot_write_1g() -> list[Result]:
    """A 1 GB snapshot written while the buffer goes on: its time, and messages lost live."""
    fill = WRITE_BYTES / IMAGE / IMAGE_RATE + 2  # seconds until the buffer holds 1 GB
    run = fill + 20  # the small topic goes on well past the write
    images = [
        cpp_peer("pub_rate"),
        "/snap_img",
        "sensor_msgs/Image",
        str(IMAGE),
        str(IMAGE_RATE),
        str(fill + 1),
        "--wait-subscribers",
        "2",
        "--linger",
        "2",
    ]
    small = [cpp_peer("multi_pub", PEERS), "/snap_small_", "1", "16", "1000", str(run),
             "--wait-subscribers", "2", "--linger", "2"]  # fmt: skip
    recorders = _recorders()
    recorders["snapshot"][recorders["snapshot"].index("--size") + 1] = "1400"
    with master() as uri:
        env = ros_env(uri)
        procs, samplers = _start_all(env, recorders)
        try:
            pubs = [start(argv, env, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
                    for argv in (images, small)]  # fmt: skip
            try:
                _wait_subscribed(uri, procs, "/snap_small_", 1)
                began = time.monotonic()
                while time.monotonic() - began < fill and pubs[0].poll() is None:
                    time.sleep(0.1)  # the publisher's own clock: 1 GB offered by now
                before = f"{WRITE_BYTES / IMAGE / IMAGE_RATE:.2f}"
                took, big = _trigger(env, "-O", "big.bag", "--topics", "/snap_img",
                                     "--before", before)  # fmt: skip
                outs = [p.communicate(timeout=run + 300)[0] for p in pubs]
                _, kept = _trigger(env, "-O", "small.bag", "--topics", "/snap_small_0")
            finally:
                for pub in pubs:
                    stop(pub)
        finally:
            _stop_all(procs, samplers)
    published = int(_truth(outs[1])["published"])
    lost = {"snapshot": published - int(kept["messages"]),  # type: ignore[call-overload]
            "record": published - _count(BUILD / "record.bag", "/snap_small_")}  # fmt: skip
    written = int(big["bytes"])  # type: ignore[call-overload]
    for name in ("big.bag", "small.bag"):
        (BUILD / name).unlink(missing_ok=True)
    cache = _page_cache_mb_s()
    inside = float(big["seconds"])  # type: ignore[arg-type]
    note = (
        f"{written / 1e9:.2f} GB of 1 MB images ({big['messages']} messages): {inside:.1f} s in "
        f"the recorder from the trigger to the rename ({written / inside / 1e6:.0f} MB/s), "
        f"{took:.1f} s for bag trigger from its start to its answer, while 50 MB/s of images "
        f"and 1 kHz of small messages went on into both recorders; 'ROS 1' is the time this "
        f"machine's page cache takes for as many bytes ({cache:.0f} MB/s)"
    )
    return [
        Result("snapshot: write 1 GB", "s", inside, written / cache / 1e6, "-", None, note),
        Result(
            "snapshot vs record: small messages lost live during a 1 GB write", "msgs",
            lost["snapshot"], lost["record"], "0", lost["snapshot"] == 0,
            f"{published:,} published at 1 kHz over {run:.0f} s; 'ROS 1' is bag record",
        ),
    ]  # fmt: skip


FOUR_TOPIC = "/snap_four_"  # the images go on FOUR_TOPIC + "0"
FOUR_RATE = 70.0
FOUR_SIZE_MB = 40
FOUR_FILES = 4
FOUR_BEFORE, FOUR_AFTER = 0.3, 3.0
BATCH_MB = 4  # snapshot_live.BATCH_BYTES: what a file's thread holds beyond the queue


def snapshot_bound_mb(idle_mb: float, size_mb: float, files: int) -> float:
    """The bound (docs/bag.md) on a snapshot recorder's memory while ``files`` are written.

    The process idle, the buffer (--size), the live queue all files share (--size), the part
    of the buffer each file has yet to write (--size at most), and each file's batch in hand.
    """
    return idle_mb + size_mb * (2 + files) + BATCH_MB * files


def _stamps(path: Path) -> list[float]:
    """The header stamps of the images in ``path``, sorted (each image has its own)."""
    from rostools.bag.formats.access import open_bag

    with open_bag(path) as reader:
        stamps = [int.from_bytes(d[4:8], "little") + int.from_bytes(d[8:12], "little") / 1e9
                  for _, _, d in reader.messages()]  # fmt: skip
    return sorted(stamps)


def _missing(got: list[float], everything: list[float]) -> int:
    """Images of ``everything`` (rosbag record's) between ``got``'s first and last, not in it."""
    if not got:
        return 0
    inside = [t for t in everything if got[0] <= t <= got[-1]]
    return len(set(inside) - set(got))


def _started(pub: subprocess.Popen[bytes]) -> None:
    """Until ``pub_rate`` says its clock started (both recorders linked)."""
    assert pub.stdout is not None
    for line in pub.stdout:
        if line.strip() == b"started":
            return
    raise RuntimeError("pub_rate ended before it started publishing")


def bench_snapshot_four_writes() -> list[Result]:
    """70 MB/s of images, --size 40, four overlapping triggers: messages lost, peak memory."""
    topic = FOUR_TOPIC + "0"
    window = FOUR_BEFORE + FOUR_AFTER
    run = 8.0 + FOUR_FILES * 0.5 + FOUR_AFTER
    images = [cpp_peer("pub_rate"), topic, "sensor_msgs/Image", str(IMAGE), str(FOUR_RATE),
              str(run), "--wait-subscribers", "2", "--linger", "2"]  # fmt: skip
    recorders = {
        "snapshot": [*rostools_cmd(), "bag", "snapshot", topic, "-F", "json", "-L", "0",
                     "--size", str(FOUR_SIZE_MB), "-d", "600", "__name:=bench_snap"],
        "rosbag": ["rosbag", "record", topic, "-O", "peer.bag"],
    }  # fmt: skip
    with master() as uri:
        env = ros_env(uri)
        procs, samplers = _start_all(env, recorders)
        try:
            pub = start(images, env, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
            try:
                _wait_subscribed(uri, procs, FOUR_TOPIC, 1)
                idle_mb = status_kb(procs["snapshot"].pid) / 1024
                _started(pub)
                time.sleep(2.0)  # the buffer fills (--size 40 at 70 MB/s: 0.6 s)
                triggers = []
                for i in range(FOUR_FILES):
                    triggers.append(subprocess.Popen(
                        [*rostools_cmd(), "bag", "trigger", "/bench_snap", "-F", "json", "-O",
                         f"four{i}.bag", "--before", str(FOUR_BEFORE), "--after", str(FOUR_AFTER)],
                        env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=BUILD,
                    ))  # fmt: skip
                    time.sleep(0.5)
                answers = [t.communicate(timeout=300) for t in triggers]
                codes = [t.returncode for t in triggers]
                pub_out, _ = pub.communicate(timeout=run + 300)
            finally:
                stop(pub)
        finally:
            peaks = _stop_all(procs, samplers)
    published = int(_truth(pub_out)["published"])
    summaries = [json.loads(out) for out, _ in answers if out.strip()]
    if len(summaries) != FOUR_FILES:
        errors = [err.decode()[-300:] for _, err in answers]
        raise RuntimeError(f"bag trigger gave no summary: {errors}")
    got = [int(s["messages"]) + int(s.get("lost", s["drops"])) for s in summaries]
    if min(got) < 0.9 * FOUR_RATE * window:  # the flood had not begun, or lost uncounted
        raise RuntimeError(f"files short of their window: {summaries}")
    lost = sum(int(s.get("lost", s["drops"])) for s in summaries)  # an older recorder: drops only
    everything = _stamps(BUILD / "peer.bag")
    gaps, windows = 0, []
    for i, summary in enumerate(summaries):
        got = _stamps(BUILD / f"four{i}.bag")
        gaps += _missing(got, everything)
        evicted = summary.get("evicted", "?")
        windows.append(f"{len(got)} ({evicted} evicted, {summary['drops']} dropped)")
        (BUILD / f"four{i}.bag").unlink()
    peer_lost = published - _count(BUILD / "peer.bag", topic)
    bound = snapshot_bound_mb(idle_mb, FOUR_SIZE_MB, FOUR_FILES)
    peak = peaks["snapshot"] / 1024
    setup = (
        f"1 MB images at {FOUR_RATE:g} Hz from roscpp pub_rate, {published} published over "
        f"{run:g} s; bag snapshot --size {FOUR_SIZE_MB}; {FOUR_FILES} bag trigger --before "
        f"{FOUR_BEFORE:g} --after {FOUR_AFTER:g}, 0.5 s apart (exit codes {codes})"
    )
    return [
        Result(
            "snapshot: messages lost, four overlapping writes at 70 MB/s", "msgs", lost,
            peer_lost, "0", lost == 0 and gaps == 0,
            f"{setup}; messages per file: {', '.join(windows)}; images rosbag record has between "
            f"a file's first and last that the file lacks: {gaps}; 'ROS 1' is what rosbag "
            "record lost of the whole flood, in the same run",
        ),
        Result(
            f"snapshot peak RSS, four writes at 70 MB/s, --size {FOUR_SIZE_MB}", "MB", peak,
            peaks["rosbag"] / 1024, f"<= {bound:.0f} MB (the docs' bound)", peak <= bound,
            f"{setup}; bound = idle {idle_mb:.0f} MB + {FOUR_SIZE_MB} MB x (2 + "
            f"{FOUR_FILES}) + {BATCH_MB} MB x {FOUR_FILES}; 'ROS 1' is rosbag record's peak",
        ),
    ]  # fmt: skip


BENCHMARKS = {
    "snapshot_buffering": bench_snapshot_buffering,
    "snapshot_write_1g": bench_snapshot_write_1g,
    "snapshot_four_writes": bench_snapshot_four_writes,
}
