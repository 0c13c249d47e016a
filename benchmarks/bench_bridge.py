"""``rostools bridge`` beside a direct TCPROS subscriber and foxglove-sdk's server, in one run.

``bridge_throughput``: a roscpp publisher (``peers/pub_sensors.cpp``) sends 1 MB
``sensor_msgs/Image`` at 30 Hz, then (another publisher, later in the run) a
``sensor_msgs/PointCloud2`` of 1M points of 16 bytes (16 MB) at 10 Hz, each stamped with the
wall-clock time of its publish. Each topic goes, in turn, to 1 and to 4 readers of:

- ``direct``: TCPROS subscribers (rostools' node, raw frames), a process each: the ceiling;
- ``bridge``: ``rostools bridge TOPIC``, read by WebSocket clients (Python ``websockets``, a
  process each, so that no client's CPU holds the server back: ``peers/bridge_peers.py``);
- ``foxglove``: foxglove-sdk's Rust WebSocket server, fed each message's raw bytes by a
  rostools subscriber in its process, read by the same clients.

So the publisher, the clients and the ROS side are the same; only the server differs. Each
reader counts what arrives in one window of WINDOW seconds that starts WARMUP seconds after
the last reader had its first message: the throughput is the ROS bytes all readers got a
second; a delay is a message's arrival (wall clock) less its ``header.stamp``, pooled over the
readers; the CPU is the server process's (user + system, all threads) over the window, in %
of one core. Goals: at least 90% of the direct subscribers' throughput, and foxglove-sdk's.

``bridge_slow_client``: 4 clients of the image topic, one reading 1 MB/s (it sleeps after each
message, so its socket fills and the bridge's queue for it drops), three at full speed. The
three must keep the rate of one client alone (measured first, in the same run), and the
bridge's resident memory (sampled every 0.1 s) must stay within the bound its queues set.

Every process is stopped through its PID, all on loopback. The readers' Python is the one
running this (it needs ``websockets``, and the foxglove peer ``foxglove-sdk``, the test
extra); the bridge and the direct subscribers run from the benchmark install
(``benchmarks/.venv``).
"""

from __future__ import annotations

import contextlib
import json
import os
import queue
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO

from benchmarks.common import (
    BENCH_VENV,
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

PEERS = Path(__file__).with_name("peers")
WARMUP = 2.0  # seconds between the last reader's first message and the window
WINDOW = 6.0  # seconds counted
SLOW_WINDOW = 12.0  # seconds counted in the slow-client case
SLOW_RATE = 1e6  # bytes a second the slow client reads
READERS = (1, 4)
START_TIMEOUT = 60.0  # seconds for a process to say it is ready (a loaded machine)
MB = 1e6


@dataclass(frozen=True)
class Topic:
    """A topic of the run and its publisher's settings."""

    name: str
    kind: str  # pub_sensors' KIND
    type: str
    rate: float
    size: int  # bytes of one serialised message, about

    @property
    def label(self) -> str:
        """How the results name it."""
        return f"{self.size / MB:g} MB {'images' if self.kind == 'image' else 'point clouds'}"


IMAGE = Topic("/camera/image", "image", "sensor_msgs/Image", 30.0, 1_000_000)
CLOUD = Topic("/lidar/points", "cloud", "sensor_msgs/PointCloud2", 10.0, 16_000_000)


class Peer:
    """A process of the run: its stdout as lines, its stderr kept for the error message."""

    def __init__(self, argv: list[str], env: dict[str, str], stdin: bool = False) -> None:
        self.argv = argv
        self.err: IO[bytes] = tempfile.TemporaryFile()  # noqa: SIM115 - closed in stop()
        self.proc = start(
            argv,
            env,
            stdin=subprocess.PIPE if stdin else subprocess.DEVNULL,
            stdout=subprocess.PIPE,
            stderr=self.err,
        )
        self.lines: queue.Queue[str | None] = queue.Queue()
        threading.Thread(target=self._pump, daemon=True).start()

    def _pump(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self.lines.put(line.decode(errors="replace").strip())
        self.lines.put(None)

    def expect(self, test: Callable[[str], bool], timeout: float) -> str:
        """The first line from now on that passes ``test``."""
        deadline = time.monotonic() + timeout
        while True:
            try:
                line = self.lines.get(timeout=max(deadline - time.monotonic(), 0.01))
            except queue.Empty:
                raise RuntimeError(f"{self.name}: nothing after {timeout:.0f} s") from None
            if line is None:
                self.proc.wait(5)
                self.err.seek(0)
                tail = self.err.read().decode(errors="replace")[-800:]
                raise RuntimeError(f"{self.name} exited ({self.proc.returncode}): {tail}")
            if test(line):
                return line

    def tell(self, line: str) -> None:
        """One line on its stdin."""
        assert self.proc.stdin is not None
        self.proc.stdin.write(line.encode() + b"\n")
        self.proc.stdin.flush()

    @property
    def name(self) -> str:
        """For error messages."""
        return " ".join(Path(a).name if "/" in a else a for a in self.argv[:3])

    def stop(self) -> None:
        """Stop it by its PID."""
        stop(self.proc)
        self.err.close()


@dataclass
class Figures:
    """One server, one topic, some readers: what the window saw."""

    per_reader: list[float]  # MB/s of each reader
    messages: list[int]  # messages each reader got in the window
    delays_by_reader: list[list[float]]  # ms
    cpu: float | None  # % of one core, the server's
    rss_kb: list[tuple[float, int]] = field(default_factory=list)  # (s into window, VmRSS)
    rss_idle_kb: int = 0  # before any reader connected
    readers_cpu: list[float] = field(default_factory=list)  # % of one core, each reader's
    dropped: list[int] = field(default_factory=list)  # the bridge's drops, for each client
    duplicates: int = 0  # messages a reader got twice (none expected)
    load: float = 0.0  # the machine's 1-minute load average as the window ended

    @property
    def delays_ms(self) -> list[float]:
        """Every reader's delays, in ms."""
        return [d for each in self.delays_by_reader for d in each]

    @property
    def rate(self) -> float:
        """MB/s over all readers."""
        return sum(self.per_reader)

    def delay(self, q: float, readers: slice = slice(None)) -> float:
        """A quantile of the delays of some readers (all: pooled), in ms."""
        ordered = sorted(d for each in self.delays_by_reader[readers] for d in each)
        return ordered[min(int(q * len(ordered)), len(ordered) - 1)] if ordered else float("nan")


def _python(module: str) -> str | None:
    """A Python that imports ``module``: the benchmark install's, else this one's."""
    for exe in (str(BENCH_VENV / "bin" / "python"), sys.executable):
        probe = [exe, "-c", f"import {module}"]
        if subprocess.run(probe, capture_output=True, check=False).returncode == 0:
            return exe
    return None


@contextlib.contextmanager
def _publisher(topic: Topic, env: dict[str, str]) -> Iterator[None]:
    argv = [cpp_peer("pub_sensors", PEERS), topic.name, topic.kind, str(topic.rate)]
    pub = Peer(argv, env)
    try:
        pub.expect(lambda line: line == "ready", START_TIMEOUT)
        yield
    finally:
        pub.stop()


@dataclass
class Run:
    """The processes' settings for one module run."""

    uri: str
    env: dict[str, str]
    bridge: list[str]
    ours_py: str  # the direct subscribers'
    fox_py: str | None  # the foxglove peer's
    reader_py: str

    def server(self, kind: str, topic: Topic) -> tuple[Peer, str]:
        """Start a server; it and its URL once it listens."""
        if kind == "bridge":
            argv = [*self.bridge, "bridge", topic.name, "--port", "0", "--format", "json"]
            peer = Peer([*argv, "--address", "127.0.0.1", "--quiet"], self.env)
            line = peer.expect(lambda s: '"listening"' in s, START_TIMEOUT)
            return peer, str(json.loads(line)["url"])
        assert self.fox_py is not None
        argv = [self.fox_py, str(PEERS / "bridge_peers.py"), "foxglove", self.uri, topic.name]
        peer = Peer([*argv, topic.type], self.env)
        port = json.loads(peer.expect(lambda s: s.startswith("{"), START_TIMEOUT))["port"]
        return peer, f"ws://127.0.0.1:{port}"

    def phase(
        self, kind: str, topic: Topic, readers: int, slow: bool = False, window: float = WINDOW
    ) -> Figures:
        """One measurement: ``kind`` (direct, bridge, foxglove) serving ``readers``."""
        server, url = self.server(kind, topic) if kind != "direct" else (None, "")
        peers: list[Peer] = []
        try:
            idle = status_kb(server.proc.pid) if server else 0
            script = str(PEERS / "bridge_peers.py")
            for i in range(readers):
                if kind == "direct":
                    argv = [self.ours_py, script, "direct", self.uri, topic.name]
                else:
                    argv = [self.reader_py, script, "reader", url, topic.name]
                    argv += ["--slow", str(SLOW_RATE)] if slow and i == 0 else []
                peers.append(Peer(argv, self.env, stdin=True))
            for p in peers:
                p.expect(lambda s: s == "ready", START_TIMEOUT)
            t0 = time.time_ns() + int(WARMUP * 1e9)
            t1 = t0 + int(window * 1e9)
            for p in peers:
                p.tell(f"{t0} {t1}")
            time.sleep(max(t0 - time.time_ns(), 0) / 1e9)
            pid = server.proc.pid if server else 0
            cpu0 = cpu_seconds(pid) if server else 0.0
            readers0 = [cpu_seconds(p.proc.pid) for p in peers]
            rss: list[tuple[float, int]] = []
            while (left := t1 - time.time_ns()) > 0:
                if server:
                    rss.append(((time.time_ns() - t0) / 1e9, status_kb(pid)))
                time.sleep(min(0.1, left / 1e9))
            cpu = (cpu_seconds(pid) - cpu0) / window * 100 if server else None
            load = os.getloadavg()[0]
            readers_cpu = [
                (cpu_seconds(p.proc.pid) - c) / window * 100
                for p, c in zip(peers, readers0, strict=True)
            ]
            outs = [json.loads(p.expect(lambda s: s.startswith("{"), 60)) for p in peers]
            for p in peers:
                p.stop()
            gone = [server.expect(_gone, 30) for _ in peers] if kind == "bridge" and server else []
        finally:
            for p in peers:
                p.stop()
            if server:
                server.stop()
        return Figures(
            [o["bytes"] / window / MB for o in outs],
            [o["messages"] for o in outs],
            [[d / 1e6 for d in o["delays_ns"]] for o in outs],
            cpu,
            rss,
            idle,
            readers_cpu,
            [json.loads(line)["dropped"] for line in gone],
            sum(o["duplicates"] for o in outs),
            load,
        )


def _gone(line: str) -> bool:
    return '"disconnected"' in line


def _run() -> Run:
    ours_py = str(BENCH_VENV / "bin" / "python")
    return Run("", {}, rostools_cmd(), ours_py, _python("foxglove"), sys.executable)


def _topic_results(topic: Topic, run: Run) -> list[Result]:
    """The three servers, 1 and 4 readers, one topic."""
    results: list[Result] = []
    with _publisher(topic, run.env):
        for n in READERS:
            got = {"direct": run.phase("direct", topic, n), "bridge": run.phase("bridge", topic, n)}
            if run.fox_py:
                got["foxglove"] = run.phase("foxglove", topic, n)
            results += _compare(topic, n, got)
    return results


def _compare(topic: Topic, n: int, got: dict[str, Figures]) -> list[Result]:
    ours, direct, fox = got["bridge"], got["direct"], got.get("foxglove")
    where = f"{topic.label} at {topic.rate:g} Hz to {n} client{'s' if n > 1 else ''}"
    offered = topic.size * topic.rate * n / MB

    def rates(f: Figures) -> str:
        each = f" ({', '.join(f'{r:.0f}' for r in f.per_reader)})" if n > 1 else ""
        cpu = statistics.mean(f.readers_cpu)
        return f"{f.rate:.0f} MB/s{each}, a reader's CPU {cpu:.0f}%"

    fox_note = f"; foxglove-sdk {rates(fox)}" if fox else ""
    drops = f", dropped {sum(ours.dropped)}" if ours.dropped else ""
    twice = {k: f.duplicates for k, f in got.items() if f.duplicates}
    drops += f"; MESSAGES SENT TWICE: {twice}" if twice else ""
    out = [
        Result(
            f"bridge throughput, {where}, vs direct TCPROS",
            "MB/s",
            ours.rate,
            direct.rate,
            ">= 0.9x direct",
            ours.rate >= 0.9 * direct.rate,
            f"offered {offered:.0f} MB/s; bridge {rates(ours)}{drops}; direct {rates(direct)}"
            f"{fox_note}; load average {ours.load:.1f} on {os.cpu_count()} cores",
        )
    ]
    if fox is not None:
        out.append(
            Result(
                f"bridge throughput, {where}, vs foxglove-sdk",
                "MB/s",
                ours.rate,
                fox.rate,
                ">= foxglove-sdk (less a message a reader)",
                sum(ours.messages) >= sum(fox.messages) - n,
                f"messages in the window: bridge {sum(ours.messages)}, foxglove-sdk "
                f"{sum(fox.messages)}, direct {sum(direct.messages)}",
            )
        )
    for q, label in ((0.5, "p50"), (0.99, "p99")):
        out.append(
            Result(
                f"bridge delay {label}, {where}, vs foxglove-sdk",
                "ms",
                ours.delay(q),
                fox.delay(q) if fox else None,
                "report",
                None,
                f"publish (header.stamp) to client receive, over {len(ours.delays_ms)} "
                f"messages; direct TCPROS {direct.delay(q):.1f} ms",
            )
        )
    out.append(
        Result(
            f"bridge CPU, {where}, vs foxglove-sdk",
            "% core",
            ours.cpu or 0.0,
            fox.cpu if fox else None,
            "report",
            None,
            "the server process over the window (user + system, all threads); foxglove-sdk's "
            "includes its rostools subscriber and a copy of each message into the SDK",
        )
    )
    return out


def bench_throughput() -> list[Result]:
    """Images, then point clouds, to 1 and 4 readers of each server."""
    run = _run()
    with master() as uri:
        run.uri, run.env = uri, ros_env(uri)
        return _topic_results(IMAGE, run) + _topic_results(CLOUD, run)


def bench_slow_client() -> list[Result]:
    """4 image clients, one reading at 1 MB/s: the others' rate and the bridge's memory."""
    from rostools.web.client import QUEUE_BYTES
    from rostools.web.server import WRITE_LIMIT

    run = _run()
    with master() as uri:
        run.uri, run.env = uri, ros_env(uri)
        with _publisher(IMAGE, run.env):
            alone = run.phase("bridge", IMAGE, 1)
            f = run.phase("bridge", IMAGE, 4, slow=True, window=SLOW_WINDOW)
    fast = f.per_reader[1:]
    kept = statistics.mean(fast)
    # Frames are shared, not copied, between the clients' queues. The slow client's queue
    # holds at most QUEUE_BYTES; each client's socket may buffer WRITE_LIMIT and the message
    # being written; the subscription holds the message being received, and the writer the
    # one in hand. Allocator slack is not in the bound.
    message = IMAGE.size
    bound = QUEUE_BYTES + 4 * (WRITE_LIMIT + message) + 2 * message
    rss = [kb for _, kb in f.rss_kb]
    rise = (max(rss) - f.rss_idle_kb) * 1024 / MB
    half = len(rss) // 2
    growth = (max(rss[half:]) - max(rss[:half])) * 1024 / MB
    return [
        Result(
            "bridge slow client: 3 full-speed image clients beside one at 1 MB/s, vs 1 client",
            "MB/s",
            kept,
            alone.rate,
            ">= 0.95x the 1-client rate",
            kept >= 0.95 * alone.rate,
            f"the three: {', '.join(f'{r:.1f}' for r in fast)} MB/s; the slow one read "
            f"{f.per_reader[0]:.2f} MB/s; the bridge dropped {max(f.dropped, default=0)} for "
            f"it, {sum(f.dropped) - max(f.dropped, default=0)} for the others; the three's p50/p99 "
            f"delay {f.delay(0.5, slice(1, None)):.1f}/"
            f"{f.delay(0.99, slice(1, None)):.1f} ms (alone {alone.delay(0.5):.1f}/"
            f"{alone.delay(0.99):.1f}); over {SLOW_WINDOW:g} s",
        ),
        Result(
            "bridge slow client: peak RSS above idle, 4 image clients, one at 1 MB/s",
            "MB",
            rise,
            bound / MB,
            "<= the queues' bound (theirs)",
            rise <= bound / MB,
            f"idle {f.rss_idle_kb / 1024:.0f} MB, window start {rss[0] / 1024:.0f} MB, peak "
            f"{max(rss) / 1024:.0f} MB, end {rss[-1] / 1024:.0f} MB; second half's peak less the "
            f"first's: {growth:+.1f} MB; bound: QUEUE_BYTES + 4 x (WRITE_LIMIT + a message) + 2 "
            "messages",
        ),
    ]


BENCHMARKS = {"bridge_throughput": bench_throughput, "bridge_slow_client": bench_slow_client}
