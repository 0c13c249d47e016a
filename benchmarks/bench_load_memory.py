"""Memory under load: ``bag record -a`` of 1,000 quiet topics beside ``rosbag record -a``.

``load_record_1000_topics``: one roscpp publisher (``benchmarks/peers/multi_pub.cpp``) offers
1,000 topics at 10 Hz each (16-byte std_msgs/String) for DURATION seconds
(``ROSTOOLS_BENCH_LOAD_SECONDS``, default 60) to ``rostools bag record -a`` and the C++
``rosbag record -a`` at once, on one rosmaster: the publisher starts its clock only once both
recorders are connected on every topic, so both are offered the same messages. Each
recorder's peak resident memory (the most of VmRSS and VmHWM, sampled from /proc every 0.1 s
from its start to its exit) is reported, and each bag is counted against what the publisher
says it sent. The publisher's own rate and lateness are in the note, to show it kept up.

Most of a recorder's memory here is what each of its 1,000 connections costs, not messages:
the benchmark of issue 24's "memory per connection".

The master gets a free loopback port; every process is stopped through its PID. Bags go to
benchmarks/build/load_memory/ (gitignored) and are deleted once counted.
"""

from __future__ import annotations

import json
import os
import subprocess
import time
from dataclasses import dataclass
from pathlib import Path

from benchmarks.bench_bag_live import _finish, _rosbag
from benchmarks.bench_load import _Client, _PeakRss, _wait_drained
from benchmarks.common import ROOT, Result, cpp_peer, master, ros_env, rostools_cmd, start, stop

BUILD = ROOT / "benchmarks" / "build" / "load_memory"
PEERS = Path(__file__).with_name("peers")

DURATION = float(os.environ.get("ROSTOOLS_BENCH_LOAD_SECONDS", "60"))
TOPICS = 1000
RATE = 10.0  # messages per second on every topic
SIZE = 16  # bytes of std_msgs/String data
PREFIX = "/load_mem_"
SUBSCRIBE_TIMEOUT = 120.0  # seconds for both recorders to subscribe to every topic
LINGER = 2.0  # seconds the publisher stays up after its run, so its queues reach the recorders
CLOSE_TIMEOUT = 120.0  # seconds a recorder may take to close its file after SIGINT
RSS_TARGET = 2.0  # our peak at most this many times rosbag's
KEPT_TARGET = 99.9  # percent


@dataclass
class _Kept:
    """What one recorder made of the run."""

    recorded: int
    fewest: int  # messages of the topic with fewest in the file
    topics: int  # load topics in the file
    peak_rss_kb: int
    close_s: float  # seconds from SIGINT until the recorder exited


def _wait_subscribed(
    uri: str,
    recorders: dict[str, subprocess.Popen[bytes]],
    prefix: str = PREFIX,
    topics: int = TOPICS,
) -> None:
    """Until the master lists every recorder as a subscriber of every load topic."""
    client = _Client(uri)
    wanted = {f"{prefix}{i}" for i in range(topics)}
    deadline = time.monotonic() + SUBSCRIBE_TIMEOUT
    try:
        while True:
            for label, rec in recorders.items():
                if rec.poll() is not None:
                    raise RuntimeError(f"{label} exited ({rec.returncode}); see {BUILD}")
            _, _, (_, subscribers, _) = client.call("getSystemState", "/bench_load_memory")
            short = {t for t, nodes in subscribers if len(nodes) >= len(recorders)}
            missing = wanted - short
            if not missing:
                return
            if time.monotonic() > deadline:
                raise RuntimeError(
                    f"after {SUBSCRIBE_TIMEOUT:.0f} s, {len(missing)} of {topics} topics lack "
                    f"{len(recorders)} subscribers; see {BUILD}"
                )
            time.sleep(0.5)
    finally:
        client.close()


def _count(out: Path) -> tuple[int, int, int]:
    """Messages on the load topics in ``out``, the fewest on one topic, and how many topics."""
    from rostools.bag.formats.access import bag_info

    if not out.exists():
        raise RuntimeError(f"no {out.name} was written; see {BUILD}")
    info = bag_info(out)
    counts = {t.topic: t.messages for t in info.topics if t.topic.startswith(PREFIX)}
    out.unlink()
    return sum(counts.values()), min(counts.values(), default=0), len(counts)


def _run(recorders: dict[str, tuple[list[str], Path]]) -> tuple[dict[str, _Kept], dict[str, float]]:
    """One publishing run into every recorder at once; what each kept, and the publisher's truth."""
    BUILD.mkdir(parents=True, exist_ok=True)
    for _, out in recorders.values():
        out.unlink(missing_ok=True)
        out.with_name(out.name + ".active").unlink(missing_ok=True)
    publisher = [
        cpp_peer("multi_pub", PEERS), PREFIX, str(TOPICS), str(SIZE), str(RATE), str(DURATION),
        "--wait-subscribers", str(len(recorders)), "--wait-timeout", str(SUBSCRIBE_TIMEOUT + 30),
        "--linger", str(LINGER),
    ]  # fmt: skip
    procs: dict[str, subprocess.Popen[bytes]] = {}
    samplers: dict[str, _PeakRss] = {}
    closed: dict[str, float] = {}
    with master() as uri:
        env = ros_env(uri)
        try:
            for label, (argv, _) in recorders.items():
                log = (BUILD / f"{label}.log").open("wb")
                procs[label] = start(argv, env, stdout=log, stderr=subprocess.STDOUT, cwd=BUILD)
                log.close()
                samplers[label] = _PeakRss(procs[label].pid)
                samplers[label].start()
            pub = start(publisher, env, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
            try:
                _wait_subscribed(uri, procs)
                timeout = SUBSCRIBE_TIMEOUT + DURATION + LINGER + 120
                pub_out, pub_err = pub.communicate(timeout=timeout)
                if pub.returncode != 0:
                    raise RuntimeError(f"multi_pub failed: {pub_err.decode()[-500:]}")
            finally:
                stop(pub)
            for label, (_, out) in recorders.items():
                _wait_drained(procs[label], out)
        finally:
            for label, proc in procs.items():
                began = time.monotonic()
                _finish(proc, CLOSE_TIMEOUT)
                closed[label] = time.monotonic() - began
    truth: dict[str, float] = json.loads(
        [ln for ln in pub_out.decode().splitlines() if ln.startswith("{")][-1]
    )
    kept = {}
    for label, (_, out) in recorders.items():
        recorded, fewest, topics = _count(out)
        kept[label] = _Kept(recorded, fewest, topics, samplers[label].stop(), closed[label])
    return kept, truth


def bench_record_1000_topics() -> list[Result]:
    """1,000 topics x 10 Hz into ``bag record -a`` and ``rosbag record -a``: peak RSS, kept."""
    ours_argv = [*rostools_cmd(), "bag", "record", "-q", "-a", "-O", "ours.bag"]
    recorders = {"ours": (ours_argv, BUILD / "ours.bag")}
    theirs_cmd = _rosbag("record")
    if theirs_cmd is not None:
        recorders["rosbag"] = ([*theirs_cmd, "-q", "-a", "-O", "theirs.bag"], BUILD / "theirs.bag")
    got, truth = _run(recorders)
    published = int(truth["published"])
    ours, theirs = got["ours"], got.get("rosbag")

    def kept(k: _Kept) -> float:
        return 100.0 * k.recorded / published if published else 0.0

    setup = (
        f"{TOPICS} topics x {RATE:g} Hz, {SIZE}-byte std_msgs/String, {DURATION:g} s, one roscpp "
        f"multi_pub into both recorders at once, rosmaster; the publisher held "
        f"{truth['rate']:,.0f} msg/s (asked {TOPICS * RATE:,.0f}), at most "
        f"{int(truth['behind_max'])} rounds late"
    )
    note = "; ".join(
        f"{label}: {k.recorded:,} of {published:,} ({k.topics} topics, fewest {k.fewest:,}), "
        f"peak {k.peak_rss_kb / 1024:.0f} MB, closed in {k.close_s:.1f} s"
        for label, k in got.items()
    )
    ratio = None if theirs is None else ours.peak_rss_kb / theirs.peak_rss_kb
    return [
        Result(
            "load record -a 1000 topics x 10 Hz, recorder peak RSS",
            "MB",
            ours.peak_rss_kb / 1024,
            None if theirs is None else theirs.peak_rss_kb / 1024,
            f"<= {RSS_TARGET:g}x rosbag",
            None if ratio is None else ratio <= RSS_TARGET,
            f"{setup}; max of VmRSS/VmHWM sampled every 0.1 s from start to exit; {note}",
        ),
        Result(
            "load record -a 1000 topics x 10 Hz, kept",
            "%",
            kept(ours),
            None if theirs is None else kept(theirs),
            f">= {KEPT_TARGET}%",
            kept(ours) >= KEPT_TARGET,
            f"{setup}; {note}",
        ),
    ]


BENCHMARKS = {
    "load_record_1000_topics": bench_record_1000_topics,
}
