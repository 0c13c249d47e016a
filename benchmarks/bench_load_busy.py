"""A busy machine: `bag record -a` of 1,000 topics with the defaults, beside `rosbag record -a`.

``load_record_1000_topics_busy``: BUSY processes spin on the CPU (``ROSTOOLS_BENCH_BUSY``,
default 12: a 2-core machine at a load of about 14) while one roscpp publisher
(``benchmarks/peers/multi_pub.cpp``) offers 1,000 topics at 10 Hz each for DURATION seconds
(``ROSTOOLS_BENCH_BUSY_SECONDS``, default 40) on rosmaster. Once it has advertised, one
recorder starts with its defaults (our master calls wait ``ROSTOOLS_MASTER_TIMEOUT``, 3 s):
``rostools bag record -a`` to ``.bag``, the same to MCAP, and the C++ ``rosbag record -a``, a
round each, on a fresh master and publisher. Reported: how many of the 1,000 topics each file
holds (goal: all), how long after its start the last of them was first heard, each
recorder's exit code, and the messages kept against what the publisher
sent (the recorder starts after the publisher, so the first seconds of each topic are not
offered to it: the figure compares, it does not judge). Issue 32 saw our recorder exit 5 with
nothing recorded in 2 of 2 such runs. (Three recorders on one publisher at once measured the
publisher: under that load, roscpp's accept queue overflowed.)

Every process gets a free loopback port or none, and is stopped through its PID. Bags go to
benchmarks/build/load_busy/ (gitignored) and are deleted once counted.
"""

from __future__ import annotations

import contextlib
import json
import os
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from benchmarks.bench_bag_live import _finish, _rosbag
from benchmarks.common import ROOT, Result, cpp_peer, master, ros_env, rostools_cmd, start, stop

BUILD = ROOT / "benchmarks" / "build" / "load_busy"
PEERS = Path(__file__).with_name("peers")

BUSY = int(os.environ.get("ROSTOOLS_BENCH_BUSY", "12"))
DURATION = float(os.environ.get("ROSTOOLS_BENCH_BUSY_SECONDS", "40"))
TOPICS = 1000
RATE = 10.0
SIZE = 16
PREFIX = "/load_busy_"
READY_TIMEOUT = 120.0  # seconds for the publisher to advertise every topic
CLOSE_TIMEOUT = 120.0  # seconds a recorder may take to close its file after SIGINT


@contextlib.contextmanager
def busy(count: int) -> Iterator[None]:
    """``count`` processes that spin on the CPU while in the ``with``; stopped by PID."""
    spin = [sys.executable, "-c", "while True: pass"]
    procs = [start(spin, dict(os.environ), stderr=subprocess.DEVNULL) for _ in range(count)]
    try:
        yield
    finally:
        for proc in procs:
            stop(proc)


@dataclass
class _Outcome:
    """What one recorder made of the run."""

    code: int | None
    topics: int  # load topics in its file
    messages: int
    #: Seconds from the recorder's start to the first message of its last topic to arrive.
    attached: float | None


def _count(out: Path, started_ns: int) -> tuple[int, int, float | None]:
    """Load topics with a message in ``out``, their messages, and when the last topic's first
    message was received, in seconds after ``started_ns`` ((0, 0, None) with no file)."""
    from rostools.bag.formats.access import open_bag

    if not out.exists():
        return 0, 0, None
    firsts: dict[str, int] = {}
    messages = 0
    with contextlib.closing(open_bag(out)) as bag:
        for conn, t_ns, _ in bag.messages():
            if conn.topic.startswith(PREFIX):
                messages += 1
                firsts.setdefault(conn.topic, t_ns)
    out.unlink()
    last = (max(firsts.values()) - started_ns) / 1e9 if firsts else None
    return len(firsts), messages, last


def _wait_line(proc: subprocess.Popen[bytes], word: bytes, timeout: float) -> None:
    """Until ``proc`` prints a line that starts with ``word``."""
    assert proc.stdout is not None
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        line = proc.stdout.readline()
        if not line:
            raise RuntimeError(f"multi_pub ended before {word.decode()!r}")
        if line.startswith(word):
            return
    raise RuntimeError(f"multi_pub did not say {word.decode()!r} within {timeout:g} s")


def _round(label: str, argv: list[str], out: Path) -> tuple[_Outcome, int]:
    """One busy run into one recorder; what it made of it, and what was published."""
    BUILD.mkdir(parents=True, exist_ok=True)
    out.unlink(missing_ok=True)
    out.with_name(out.name + ".active").unlink(missing_ok=True)
    publisher = [
        cpp_peer("multi_pub", PEERS), PREFIX, str(TOPICS), str(SIZE), str(RATE), str(DURATION),
        "--linger", "2",
    ]  # fmt: skip
    with busy(BUSY), master() as uri:
        env = ros_env(uri)
        pub = start(publisher, env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
        recorder = None
        try:
            _wait_line(pub, b"ready", READY_TIMEOUT)
            with (BUILD / f"{label}.log").open("wb") as log:
                started_ns = time.time_ns()
                recorder = start(argv, env, stdout=log, stderr=subprocess.STDOUT, cwd=BUILD)
            pub_out, _ = pub.communicate(timeout=DURATION + READY_TIMEOUT + 60)
        finally:
            stop(pub)
            if recorder is not None:
                _finish(recorder, CLOSE_TIMEOUT)
    truth = json.loads([ln for ln in pub_out.decode().splitlines() if ln.startswith("{")][-1])
    topics, messages, attached = _count(out, started_ns)
    outcome = _Outcome(recorder.returncode, topics, messages, attached)
    return outcome, int(truth["published"])


def bench_record_1000_topics_busy() -> list[Result]:
    """1,000 topics x 10 Hz on a busy machine: the topics each recorder holds, of 1,000."""
    ours = [*rostools_cmd(), "bag", "record", "-q", "-a"]
    recorders = {
        "ours .bag": ([*ours, "-O", "ours.bag"], BUILD / "ours.bag"),
        "ours .mcap": ([*ours, "-O", "ours.mcap"], BUILD / "ours.mcap"),
    }
    theirs_cmd = _rosbag("record")
    if theirs_cmd is not None:
        recorders["rosbag"] = ([*theirs_cmd, "-q", "-a", "-O", "theirs.bag"], BUILD / "theirs.bag")
    got, published = {}, {}
    for label, (argv, out) in recorders.items():
        got[label], published[label] = _round(label, argv, out)
    theirs = got.get("rosbag")
    setup = (
        f"{TOPICS} topics x {RATE:g} Hz, {SIZE}-byte std_msgs/String, {DURATION:g} s, one roscpp "
        f"multi_pub on rosmaster, {BUSY} processes spinning on the CPU; one recorder a round, "
        "started once the publisher has advertised, with its defaults"
    )
    note = "; ".join(
        f"{label}: exit {o.code}, {o.topics} topics (the last first heard "
        f"{o.attached if o.attached is not None else float('nan'):.1f} s after its start), "
        f"{o.messages:,} of {published[label]:,} messages"
        for label, o in got.items()
    )
    return [
        Result(
            f"load record -a 1000 topics busy, topics recorded ({label})",
            "topics",
            o.topics,
            None if theirs is None else theirs.topics,
            f"{TOPICS}, exit 0",
            o.topics == TOPICS and o.code == 0,
            f"{setup}; {note}",
        )
        for label, o in got.items()
        if label != "rosbag"
    ]


BENCHMARKS = {
    "load_record_1000_topics_busy": bench_record_1000_topics_busy,
}
