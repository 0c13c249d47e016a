"""Load: 100 busy topics into one recorder, 1,000 nodes on one master, churn on a master.

``load_record_100_topics``: a neutral roscpp publisher (``benchmarks/peers/multi_pub.cpp``)
offers 100 topics at 1 kHz each (16-byte std_msgs/String) for DURATION seconds
(``ROSTOOLS_BENCH_LOAD_SECONDS``, default 60) to ``rostools bag record -a`` and, in a second
round on a fresh rosmaster, to the C++ ``rosbag record -a``. Each file is counted against what
the publisher says it sent; the recorder's peak resident memory is sampled from /proc.

``load_1000_nodes``: 1,000 fake nodes, one topic each, are registered on ``rostools core`` and
on ``rosmaster`` over raw XML-RPC; then getSystemState latency and whole-process
``topic list`` times are taken against each.

``load_register_cycles``: 100,000 registerPublisher + unregisterPublisher cycles on each master,
on one topic name and on a new name every cycle; the master's resident memory before and after.

``load_record_buffer``: as ``load_record_100_topics`` at 3 kHz per topic for half the time,
with ``-b 16``; the recorder's peak memory, which ``-b`` must bound.

``load_multicall_stall``: one client sends a 100,000-call ``system.multicall`` while another
calls getSystemState every 5 ms; the other's worst wait, on each master.

Every master gets a free loopback port; every process is stopped through its PID. Bags go to
benchmarks/build/load/ (gitignored) and are deleted once counted.
"""

from __future__ import annotations

import contextlib
import http.client
import json
import os
import statistics
import subprocess
import threading
import time
import xmlrpc.client
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

from benchmarks.bench_bag_live import _finish, _rosbag
from benchmarks.common import (
    ROOT,
    Result,
    cpp_peer,
    cpu_seconds,
    free_port,
    have,
    master,
    masters,
    ros_env,
    rostools_cmd,
    start,
    status_kb,
    stop,
    time_commands,
    wait_master,
)

BUILD = ROOT / "benchmarks" / "build" / "load"
PEERS = Path(__file__).with_name("peers")

# load_record_100_topics
DURATION = float(os.environ.get("ROSTOOLS_BENCH_LOAD_SECONDS", "60"))
REC_TOPICS = 100
REC_RATE = 1000.0  # messages per second on every topic
REC_SIZE = 16  # bytes of std_msgs/String data
REC_PREFIX = "/load_rec_"
SUBSCRIBE_TIMEOUT = 60.0  # seconds for a recorder to subscribe to every topic
LINGER = 2.0  # seconds the publisher stays up after its run, so its queues reach the recorder
DRAIN_QUIET = 2.0  # the recorder is drained once idle (CPU and file size) this long ...
DRAIN_TIMEOUT = 300.0  # ... or after this long
CLOSE_TIMEOUT = 300.0  # seconds a recorder may take to close its file after SIGINT
KEPT_TARGET = 99.9  # percent

# load_1000_nodes
NODES = 1000
STATE_CALLS = 200
STATE_WARMUP = 20
LIST_RUNS = 5
FAKE_API = "http://127.0.0.1:1/"  # a caller API nobody listens on; no call here contacts it

# load_register_cycles
CYCLES = 100_000
BATCH = 500  # cycles per system.multicall request
SETTLE = 2.0  # seconds between the last call and reading the master's memory
GROWTH_TARGET_MB = 5.0


# --- shared -----------------------------------------------------------------------------------


@contextlib.contextmanager
def _running(argv: Sequence[str]) -> Iterator[tuple[str, subprocess.Popen[bytes]]]:
    """A master from ``argv`` + a free port: its URI and process, stopped on exit."""
    port = free_port()
    uri = f"http://127.0.0.1:{port}/"
    proc = start(
        [*argv, str(port)], ros_env(uri), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    try:
        wait_master(uri)
        yield uri, proc
    finally:
        stop(proc)


class _Client:
    """One keep-alive HTTP connection to a master, the same client for every master.

    ``raw`` returns the reply bytes unparsed, so a timing is the master's work and the
    transfer, not the client's XML parsing.
    """

    def __init__(self, uri: str) -> None:
        parts = urlsplit(uri)
        self.conn = http.client.HTTPConnection(parts.hostname or "127.0.0.1", parts.port, 300)

    def raw(self, body: bytes) -> bytes:
        """POST one encoded request, return the whole reply body."""
        self.conn.request("POST", "/RPC2", body, {"Content-Type": "text/xml"})
        reply = self.conn.getresponse()
        data = reply.read()
        if reply.status != 200:
            raise RuntimeError(f"master answered HTTP {reply.status}: {data[:200]!r}")
        return data

    def call(self, method: str, *params: Any) -> Any:
        """One call, parsed; a fault raises."""
        (result,), _ = xmlrpc.client.loads(self.raw(xmlrpc.client.dumps(params, method).encode()))
        return result

    def multicall(self, calls: Sequence[tuple[str, tuple[Any, ...]]]) -> None:
        """``system.multicall`` of ROS API calls; raises unless every one returned code 1."""
        batch = [{"methodName": m, "params": list(p)} for m, p in calls]
        results = self.call("system.multicall", batch)
        for (method, params), got in zip(calls, results, strict=True):
            if not isinstance(got, list) or got[0][0] != 1:
                raise RuntimeError(f"{method}{params} failed: {got!r}")

    def close(self) -> None:
        """Close the connection."""
        self.conn.close()


# --- load_record_100_topics ---------------------------------------------------------------------


class _PeakRss(threading.Thread):
    """Samples a process's VmRSS and VmHWM every 0.1 s until it exits; ``peak_kb`` is the most."""

    def __init__(self, pid: int) -> None:
        super().__init__(daemon=True)
        self.pid = pid
        self.peak_kb = 0
        self.done = threading.Event()

    def run(self) -> None:
        while not self.done.wait(0.1):
            kb = max(status_kb(self.pid, "VmRSS"), status_kb(self.pid, "VmHWM"))
            if kb == 0 and not Path(f"/proc/{self.pid}").exists():
                return
            self.peak_kb = max(self.peak_kb, kb)

    def stop(self) -> int:
        """Stop sampling; the peak in kB."""
        self.done.set()
        self.join()
        return self.peak_kb


@dataclass
class _Recording:
    """What one recorder made of one publishing run."""

    published: int
    recorded: int
    fewest: int  # messages of the topic with fewest in the file
    topics: int  # load topics in the file
    peak_rss_kb: int
    offered_rate: float  # messages per second the publisher held
    behind_max: int  # rounds the publisher was ever late by
    drain_s: float  # seconds from the publisher's exit until the recorder went idle
    close_s: float  # seconds from SIGINT until the recorder exited

    @property
    def kept(self) -> float:
        """Messages in the file per message published, in percent."""
        return 100.0 * self.recorded / self.published if self.published else 0.0


def _wait_subscribed(uri: str, rec: subprocess.Popen[bytes], log: Path) -> None:
    """Until the master lists a subscriber on every load topic."""
    client = _Client(uri)
    wanted = {f"{REC_PREFIX}{i}" for i in range(REC_TOPICS)}
    deadline = time.monotonic() + SUBSCRIBE_TIMEOUT
    try:
        while True:
            if rec.poll() is not None:
                raise RuntimeError(f"the recorder exited ({rec.returncode}); see {log}")
            _, _, (_, subscribers, _) = client.call("getSystemState", "/bench_load")
            missing = wanted - {topic for topic, nodes in subscribers if nodes}
            if not missing:
                return
            if time.monotonic() > deadline:
                raise RuntimeError(
                    f"after {SUBSCRIBE_TIMEOUT:.0f} s, {len(missing)} of {REC_TOPICS} topics "
                    f"have no subscriber; see {log}"
                )
            time.sleep(0.2)
    finally:
        client.close()


def _size(out: Path) -> int:
    """Bytes written so far: the finished file, else the ``.active`` one."""
    for path in (out, out.with_name(out.name + ".active")):
        with contextlib.suppress(OSError):
            return path.stat().st_size
    return 0


def _wait_drained(rec: subprocess.Popen[bytes], out: Path) -> float:
    """Until the recorder has been idle (< 5% CPU, file not growing) for DRAIN_QUIET seconds.

    Returns the seconds waited.
    """
    step = 0.5
    began = time.monotonic()
    cpu, size, quiet = cpu_seconds(rec.pid), _size(out), 0.0
    while rec.poll() is None and time.monotonic() - began < DRAIN_TIMEOUT:
        time.sleep(step)
        with contextlib.suppress(OSError):
            now_cpu = cpu_seconds(rec.pid)
            now_size = _size(out)
            idle = now_cpu - cpu < 0.05 * step and now_size == size
            quiet = quiet + step if idle else 0.0
            cpu, size = now_cpu, now_size
        if quiet >= DRAIN_QUIET:
            break
    return time.monotonic() - began - quiet


def _record(
    recorder: Sequence[str],
    out: Path,
    tag: str,
    rate: float = REC_RATE,
    duration: float = DURATION,
) -> _Recording:
    """One round on a fresh rosmaster: ``recorder`` (writing ``out``) takes one publishing run."""
    from rostools.bag.formats.access import bag_info

    BUILD.mkdir(parents=True, exist_ok=True)
    out.unlink(missing_ok=True)
    out.with_name(out.name + ".active").unlink(missing_ok=True)
    log = BUILD / f"{tag}.log"
    publisher = [
        cpp_peer("multi_pub", PEERS),
        REC_PREFIX,
        str(REC_TOPICS),
        str(REC_SIZE),
        str(rate),
        str(duration),
        "--wait-subscribers",
        "1",
        "--wait-timeout",
        str(SUBSCRIBE_TIMEOUT + 30),
        "--linger",
        str(LINGER),
    ]
    with master() as uri, log.open("wb") as sink:
        env = ros_env(uri)
        rec = start(recorder, env, stdout=sink, stderr=subprocess.STDOUT, cwd=BUILD)
        sampler = _PeakRss(rec.pid)
        sampler.start()
        pub = start(publisher, env, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        try:
            _wait_subscribed(uri, rec, log)
            pub_out, pub_err = pub.communicate(timeout=SUBSCRIBE_TIMEOUT + duration + LINGER + 120)
            if pub.returncode != 0:
                raise RuntimeError(f"{tag}: multi_pub failed: {pub_err.decode()[-500:]}")
            drain_s = _wait_drained(rec, out)
        finally:
            stop(pub)
            closing = time.monotonic()
            _finish(rec, CLOSE_TIMEOUT)
            close_s = time.monotonic() - closing
            peak = sampler.stop()
    truth = json.loads([ln for ln in pub_out.decode().splitlines() if ln.startswith("{")][-1])
    if not out.exists():
        raise RuntimeError(f"{tag}: no {out.name} was written; see {log}")
    info = bag_info(out)
    counts = {t.topic: t.messages for t in info.topics if t.topic.startswith(REC_PREFIX)}
    out.unlink()
    return _Recording(
        published=int(truth["published"]),
        recorded=sum(counts.values()),
        fewest=min(counts.values(), default=0),
        topics=len(counts),
        peak_rss_kb=peak,
        offered_rate=float(truth["rate"]),
        behind_max=int(truth["behind_max"]),
        drain_s=drain_s,
        close_s=close_s,
    )


def _describe(name: str, r: _Recording) -> str:
    return (
        f"{name} {r.recorded:,} of {r.published:,} ({r.topics} topics, fewest {r.fewest:,}; "
        f"offered {r.offered_rate:,.0f}/s; drained {r.drain_s:.1f} s, closed {r.close_s:.1f} s)"
    )


def bench_record_100_topics() -> list[Result]:
    """100 topics x 1 kHz of small messages into ``bag record -a``: kept share and peak RSS."""
    rounds = {"ours": ([*rostools_cmd(), "bag", "record", "-q", "-a", "-O", "ours.bag"], "ours")}
    theirs_cmd = _rosbag("record")
    if theirs_cmd is not None:
        rounds["rosbag"] = ([*theirs_cmd, "-q", "-a", "-O", "theirs.bag"], "theirs")
    got = {
        label: _record(argv, BUILD / f"{stem}.bag", f"record100_{stem}")
        for label, (argv, stem) in rounds.items()
    }
    ours, theirs = got["ours"], got.get("rosbag")
    note = "; ".join(_describe(label, r) for label, r in got.items())
    setup = (
        f"{REC_TOPICS} topics x {REC_RATE:.0f} Hz, {REC_SIZE}-byte std_msgs/String, "
        f"{DURATION:g} s, roscpp multi_pub, rosmaster"
    )
    return [
        Result(
            "load record 100 topics x 1 kHz, kept",
            "%",
            ours.kept,
            None if theirs is None else theirs.kept,
            f">= {KEPT_TARGET}%",
            ours.kept >= KEPT_TARGET,
            f"{setup}: {note}",
        ),
        Result(
            "load record 100 topics x 1 kHz, recorder peak RSS",
            "MB",
            ours.peak_rss_kb / 1024,
            None if theirs is None else theirs.peak_rss_kb / 1024,
            "report",
            None,
            "max of VmRSS/VmHWM sampled every 0.1 s from start to exit",
        ),
    ]


def bench_record_buffer() -> list[Result]:
    """100 topics x 3 kHz into ``bag record -a -b 16``: the peak RSS, against rosbag's."""
    rate, duration = 3 * REC_RATE, DURATION / 2
    rounds = {"ours": [*rostools_cmd(), "bag", "record", "-q", "-a", "-b", "16", "-O", "ours.bag"]}
    theirs_cmd = _rosbag("record")
    if theirs_cmd is not None:
        rounds["rosbag"] = [*theirs_cmd, "-q", "-a", "-b", "16", "-O", "rosbag.bag"]
    got = {
        label: _record(argv, BUILD / f"{label}.bag", f"record_buffer_{label}", rate, duration)
        for label, argv in rounds.items()
    }
    ours, theirs = got["ours"], got.get("rosbag")
    note = "; ".join(_describe(label, r) for label, r in got.items())
    return [
        Result(
            "load record -b 16, 100 topics x 3 kHz, recorder peak RSS",
            "MB",
            ours.peak_rss_kb / 1024,
            None if theirs is None else theirs.peak_rss_kb / 1024,
            "<= 100 MB (-b bounds what is held)",
            ours.peak_rss_kb / 1024 <= 100,
            f"{duration:g} s, roscpp multi_pub, rosmaster: {note}",
        ),
        Result(
            "load record -b 16, 100 topics x 3 kHz, kept",
            "%",
            ours.kept,
            None if theirs is None else theirs.kept,
            "report (drops beyond -b are counted and exit 6)",
            None,
            note,
        ),
    ]


# --- load_1000_nodes ----------------------------------------------------------------------------


def _register_nodes(client: _Client) -> None:
    """NODES fake nodes /load_node_i, each publishing /load_topic_i."""
    calls = [
        ("registerPublisher", (f"/load_node_{i}", f"/load_topic_{i}", "std_msgs/String", FAKE_API))
        for i in range(NODES)
    ]
    for first in range(0, NODES, BATCH):
        client.multicall(calls[first : first + BATCH])


def _state_latency_ms(client: _Client) -> float:
    """Median ms of one getSystemState (reply read whole, not parsed) over STATE_CALLS calls."""
    state = client.call("getSystemState", "/bench_load")
    published = {topic for topic, _ in state[2][0]}
    missing = {f"/load_topic_{i}" for i in range(NODES)} - published
    if missing:
        raise RuntimeError(f"{len(missing)} registered topics are not in getSystemState")
    body = xmlrpc.client.dumps(("/bench_load",), "getSystemState").encode()
    samples = []
    for i in range(STATE_WARMUP + STATE_CALLS):
        began = time.perf_counter()
        client.raw(body)
        if i >= STATE_WARMUP:
            samples.append(time.perf_counter() - began)
    return 1000 * statistics.median(samples)


def _check_list(argv: Sequence[str], env: dict[str, str]) -> None:
    """One run of a ``topic list`` command must print every registered topic."""
    proc = subprocess.run(argv, env=env, capture_output=True, text=True, timeout=60, check=False)
    listed = set(proc.stdout.split())
    if proc.returncode != 0 or f"/load_topic_{NODES - 1}" not in listed or len(listed) < NODES:
        raise RuntimeError(f"{' '.join(argv)}: {len(listed)} lines; {proc.stderr[-300:]}")


def bench_1000_nodes() -> list[Result]:
    """1,000 nodes x 1 topic: getSystemState latency and ``topic list`` wall time."""
    tools: dict[str, Sequence[str]] = {"ours": [*rostools_cmd(), "topic", "list"]}
    if have("rostopic"):
        tools["theirs"] = ["rostopic", "list"]
    latency: dict[str, float] = {}
    lists: dict[tuple[str, str], float] = {}  # (master, tool) -> s
    for name, argv in masters().items():
        with _running(argv) as (uri, _):
            client = _Client(uri)
            try:
                _register_nodes(client)
                latency[name] = _state_latency_ms(client)
            finally:
                client.close()
            env = ros_env(uri)
            for tool_argv in tools.values():
                _check_list(tool_argv, env)
            timed = time_commands(tools, runs=LIST_RUNS, warmup=1, env=env)
            for tool, seconds in timed.items():
                lists[(name, tool)] = seconds
    theirs_state = latency.get("theirs")
    theirs_list = lists.get(("theirs", "theirs"))
    results = [
        Result(
            "load 1000 nodes, getSystemState latency (median)",
            "ms",
            latency["ours"],
            theirs_state,
            "<= 0.5x rosmaster",
            None if theirs_state is None else latency["ours"] <= 0.5 * theirs_state,
            f"{NODES} nodes x 1 topic; median of {STATE_CALLS} calls on one keep-alive "
            "connection, reply read whole but not parsed; ours = rostools core, "
            "theirs = rosmaster",
        ),
        Result(
            "load 1000 nodes, topic list wall time (each on its own master)",
            "s",
            lists[("ours", "ours")],
            theirs_list,
            "<= 0.5x rostopic list",
            None if theirs_list is None else lists[("ours", "ours")] <= 0.5 * theirs_list,
            f"median of {LIST_RUNS}, whole process: rostools topic list on rostools core vs "
            "rostopic list on rosmaster",
        ),
    ]
    for name, label in (("ours", "rostools core"), ("theirs", "rosmaster")):
        if (name, "theirs") in lists:
            results.append(
                Result(
                    f"load 1000 nodes, topic list wall time (both on {label})",
                    "s",
                    lists[(name, "ours")],
                    lists[(name, "theirs")],
                    "report",
                    None,
                    f"median of {LIST_RUNS}, whole process: rostools topic list vs rostopic list",
                )
            )
    return results


# --- load_register_cycles -----------------------------------------------------------------------


def _cycle_batches(distinct: bool, first: int, count: int) -> Iterator[bytes]:
    """Encoded multicalls of BATCH register + unregister cycles, numbered from ``first``."""
    caller = "/load_cycler"
    for low in range(first, first + count, BATCH):
        calls = []
        for i in range(low, min(low + BATCH, first + count)):
            topic = f"/cycle_{i}" if distinct else "/cycle"
            calls.append(
                {
                    "methodName": "registerPublisher",
                    "params": [caller, topic, "std_msgs/String", FAKE_API],
                }
            )
            calls.append({"methodName": "unregisterPublisher", "params": [caller, topic, FAKE_API]})
        yield xmlrpc.client.dumps((calls,), "system.multicall").encode()


def _run_cycles(client: _Client, distinct: bool, first: int, count: int) -> None:
    """``count`` cycles; raises unless every call returned code 1."""
    for body in _cycle_batches(distinct, first, count):
        (results,), _ = xmlrpc.client.loads(client.raw(body))
        assert isinstance(results, list)
        bad = [r for r in results if not isinstance(r, list) or r[0][0] != 1]
        if bad:
            raise RuntimeError(f"{len(bad)} calls of a cycle batch failed, e.g. {bad[0]!r}")


@dataclass
class _Growth:
    """A master's memory around CYCLES cycles."""

    before_kb: int
    after_kb: int
    seconds: float  # for the cycles

    @property
    def growth_mb(self) -> float:
        """After minus before, in MB."""
        return (self.after_kb - self.before_kb) / 1024


def _growth(argv: Sequence[str], distinct: bool) -> _Growth:
    """A fresh master through one warm-up batch, then CYCLES cycles; its RSS before and after.

    The warm-up (numbered below the measured cycles, so distinct names stay distinct) lets the
    master's one-time allocations for a batch of this size land before the first reading.
    """
    with _running(argv) as (uri, proc):
        client = _Client(uri)
        try:
            _run_cycles(client, distinct, -BATCH, BATCH)
            time.sleep(SETTLE)
            before = status_kb(proc.pid, "VmRSS")
            began = time.monotonic()
            _run_cycles(client, distinct, 0, CYCLES)
            seconds = time.monotonic() - began
            _, _, (publishers, _, _) = client.call("getSystemState", "/bench_load")
            left = [topic for topic, _ in publishers if topic.startswith("/cycle")]
            if left:
                raise RuntimeError(f"{len(left)} /cycle topics still have publishers")
            time.sleep(SETTLE)
            after = status_kb(proc.pid, "VmRSS")
        finally:
            client.close()
    return _Growth(before, after, seconds)


def bench_register_cycles() -> list[Result]:
    """100,000 registerPublisher + unregisterPublisher cycles: the master's RSS growth."""
    found = masters()
    results = []
    for distinct, variant in ((False, "one topic name"), (True, "a new topic name each cycle")):
        got = {name: _growth(argv, distinct) for name, argv in found.items()}
        ours, theirs = got["ours"], got.get("theirs")
        note = "; ".join(
            f"{'rostools core' if name == 'ours' else 'rosmaster'} {g.before_kb / 1024:.1f} -> "
            f"{g.after_kb / 1024:.1f} MB, {CYCLES / g.seconds:,.0f} cycles/s"
            for name, g in got.items()
        )
        results.append(
            Result(
                f"load {CYCLES:,} register/unregister cycles, master RSS growth ({variant})",
                "MB",
                ours.growth_mb,
                None if theirs is None else theirs.growth_mb,
                f"<= {GROWTH_TARGET_MB:g} MB",
                ours.growth_mb <= GROWTH_TARGET_MB,
                f"system.multicall of {BATCH} cycles per request, one keep-alive connection; "
                f"VmRSS {SETTLE:g} s after a warm-up batch and after the last; {note}",
            )
        )
    return results


# --- load_multicall_stall -----------------------------------------------------------------------

STALL_CALLS = 100_000  # calls in the one big multicall
STALL_TARGET_S = 0.2  # rosmaster, a thread per connection, keeps the others under this


def _worst_wait(argv: Sequence[str]) -> tuple[float, float, int]:
    """While one client's big multicall runs, another's worst getSystemState wait (s).

    Also returns how long the multicall took (s) and its body size (bytes).
    """
    calls = [
        {"methodName": "hasParam", "params": ["/bench_stall", f"/stall/param/number/{i}"]}
        for i in range(STALL_CALLS)
    ]
    body = xmlrpc.client.dumps((calls,), "system.multicall").encode()
    worst, stop_probe = [0.0], threading.Event()
    with _running(argv) as (uri, _):
        state = xmlrpc.client.dumps(("/bench_probe",), "getSystemState").encode()

        def probe() -> None:
            client = _Client(uri)
            try:
                while not stop_probe.is_set():
                    began = time.perf_counter()
                    client.raw(state)
                    worst[0] = max(worst[0], time.perf_counter() - began)
                    time.sleep(0.005)
            finally:
                client.close()

        prober = threading.Thread(target=probe, daemon=True)
        prober.start()
        time.sleep(0.5)  # the probe is warm before the big call starts
        big = _Client(uri)
        began = time.perf_counter()
        big.raw(body)
        took = time.perf_counter() - began
        big.close()
        time.sleep(0.2)
        stop_probe.set()
        prober.join()
    return worst[0], took, len(body)


def bench_multicall_stall() -> list[Result]:
    """One 100,000-call multicall must not stall the master for everyone else."""
    got = {name: _worst_wait(argv) for name, argv in masters().items()}
    ours, theirs = got["ours"], got.get("theirs")
    note = "; ".join(
        f"{'rostools core' if name == 'ours' else 'rosmaster'}: multicall took {took:.2f} s"
        for name, (_, took, _) in got.items()
    )
    return [
        Result(
            f"load other clients' worst wait during a {STALL_CALLS:,}-call multicall",
            "s",
            ours[0],
            None if theirs is None else theirs[0],
            f"<= {STALL_TARGET_S:g} s",
            ours[0] <= STALL_TARGET_S,
            f"{ours[2] / 1e6:.1f} MB body of hasParam calls; getSystemState every 5 ms on "
            f"another keep-alive connection; {note}",
        )
    ]


BENCHMARKS = {
    "load_multicall_stall": bench_multicall_stall,
    "load_record_buffer": bench_record_buffer,
    "load_record_100_topics": bench_record_100_topics,
    "load_1000_nodes": bench_1000_nodes,
    "load_register_cycles": bench_register_cycles,
}
