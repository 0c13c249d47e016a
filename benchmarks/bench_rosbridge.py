"""rosbridge v2 from ``rostools bridge`` beside the real rosbridge_server and direct TCPROS.

``rosbridge_throughput``: a roscpp publisher (``peers/pub_sensors.cpp``) sends 640x480 rgb8
``sensor_msgs/Image`` (921,600 bytes of pixels) at 30 Hz; then the same images at FAST_RATE,
beyond what rosbridge_server sends in JSON, so that the servers' capacities show (at 30 Hz
both carry every image); then (another publisher) a ``sensor_msgs/PointCloud2`` of 1M points
of x, y, z and a packed rgb, float32 each (16 bytes a point, 16 MB) at CLOUD_RATE. Each
message is stamped with the wall-clock time of its publish. Each load goes, in turn, to one
reader of:

- ``direct``: a TCPROS subscriber (rostools' node, raw frames): the ceiling;
- ``rosbridge_server``: rosbridge_suite 0.11.17's ``rosbridge_websocket`` (rospy, autobahn)
  on Debian's ROS 1, as ``tests/support/rosbridge.py`` starts it;
- ``rostools``: ``rostools bridge -a --protocol rosbridge``;

and each WebSocket server with each encoding a ``subscribe`` op asks for: JSON (no
``compression``), ``cbor`` and ``cbor-raw`` (the TCPROS bytes with a receive time, which
rosbridge_server 0.11.17 sends too: ``{"op": "publish", "topic", "msg": {"secs", "nsecs",
"bytes"}}``). The readers are Python ``websockets`` clients, a process each
(``peers/bridge_peers.py rosbridge``): cheaper than roslibpy, which decodes every message in
Python on Twisted; they read a JSON message's stamp from its head and decode CBOR with cbor2,
so that their CPU does not hold a server back. One server runs at a time.

Each reader counts one window of WINDOW seconds that starts WARMUP seconds after its first
message: messages a second, the WebSocket bytes; a delay is a message's arrival (wall clock)
less its ``header.stamp``; the CPU is the server process's (user + system, all threads) over
the window, in % of one core, and per message sent (which a busy machine changes less than
the rate); for rostools, what its bounded queue dropped for the client (rosbridge_server's
queue is unbounded: it falls behind instead, and its delay grows). A server that sends no
message within FIRST_TIMEOUT seconds of the subscription is reported as carrying none.
Goals (issue 35): JSON at least 3x rosbridge_server's messages a second, and cbor-raw (and
CBOR) at least 0.9x the ceiling's. Every process is stopped through its PID, all on loopback.
"""

from __future__ import annotations

import json
import os
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from benchmarks.bench_bridge import START_TIMEOUT, Figures, Peer
from benchmarks.common import (
    BENCH_VENV,
    Result,
    cpp_peer,
    cpu_seconds,
    master,
    ros_env,
    rostools_cmd,
)

PEERS = Path(__file__).with_name("peers")
SCRIPT = str(PEERS / "bridge_peers.py")
WARMUP = 2.0  # seconds between the reader's first message and the window
WINDOW = 5.0  # seconds counted
FIRST_TIMEOUT = 30.0  # seconds a server has to send its first message
CLOUD_RATE = 10.0  # Hz: the direct subscriber carries it on two cores
FAST_RATE = 400.0  # Hz of images: beyond what either server sends in JSON on two cores
ENCODINGS = ("none", "cbor", "cbor-raw")
LABEL = {"none": "JSON", "cbor": "CBOR", "cbor-raw": "cbor-raw"}
MB = 1e6


@dataclass(frozen=True)
class Load:
    """A topic of the run and its publisher's settings."""

    topic: str
    type: str
    rate: float
    args: tuple[str, ...]  # pub_sensors' KIND and options
    label: str


IMAGE = Load(
    "/camera/image_raw",
    "sensor_msgs/Image",
    30.0,
    ("image", "--width", "640", "--height", "480", "--rgb8"),
    "640x480 rgb8 images",
)
#: the same images offered faster than either server can send them in JSON: their capacities
IMAGE_FAST = Load(IMAGE.topic, IMAGE.type, FAST_RATE, IMAGE.args, IMAGE.label)
CLOUD = Load(
    "/points",
    "sensor_msgs/PointCloud2",
    CLOUD_RATE,
    ("cloud", "--points", "1000000", "--rgb"),
    "1M-point clouds (x, y, z, rgb: 16 MB)",
)


@dataclass
class Seen:
    """One reader of one server: its figures, or why it got none."""

    figures: Figures | None
    failure: str = ""

    @property
    def rate(self) -> float:
        """Messages a second in the window (0 when none came)."""
        return self.figures.messages[0] / WINDOW if self.figures else 0.0

    def delay(self, q: float) -> float | None:
        """A quantile of the delays, ms."""
        return self.figures.delay(q) if self.figures and self.figures.messages[0] else None

    @property
    def cpu_per_message(self) -> float | None:
        """The server's CPU ms for each message it sent: a machine's load changes it less."""
        f = self.figures
        if f is None or f.cpu is None or not f.messages[0]:
            return None
        return f.cpu / 100 * WINDOW / f.messages[0] * 1000

    def brief(self) -> str:
        """Its figures in a few words."""
        f = self.figures
        if f is None:
            return self.failure
        p50, p99 = self.delay(0.5), self.delay(0.99)
        delays = f"p50/p99 {p50:.0f}/{p99:.0f} ms" if p50 is not None and p99 is not None else ""
        each = self.cpu_per_message
        cpu = f", CPU {f.cpu:.0f}% ({each:.2f} ms a message)" if each is not None else ""
        extra = f", {f.duplicates} SENT TWICE" if f.duplicates else ""
        extra += f", the bridge dropped {f.dropped[0]} (its queue)" if f.dropped else ""
        return f"{self.rate:.1f} msg/s ({f.rate:.0f} MB/s), {delays}{cpu}{extra}"


@dataclass
class Server:
    """A running WebSocket server: its URL and the PID whose CPU counts."""

    url: str
    pid: int
    #: rostools bridge's event lines: its count of what it dropped for each client
    events: Peer | None = None


@dataclass
class Run:
    """The processes' settings for one run."""

    uri: str
    env: dict[str, str]
    home: Path
    ours_py: str  # the direct subscriber's
    seen: dict[tuple[str, str], Seen] = field(default_factory=dict)

    @contextmanager
    def rosbridge_server(self) -> Iterator[Server | str]:
        """The real rosbridge_server, or why it cannot run here."""
        from tests.support.rosbridge import rosbridge_missing, start_rosbridge

        if reason := rosbridge_missing():
            yield reason
            return
        bridge = start_rosbridge(self.uri, self.home)
        try:
            yield Server(bridge.url, bridge.procs[1].pid)  # rosbridge_websocket, not rosapi
        finally:
            bridge.stop()

    @contextmanager
    def rostools(self) -> Iterator[Server | str]:
        """``rostools bridge --protocol rosbridge``, or why it cannot run."""
        argv = [*rostools_cmd(), "bridge", "-a", "--protocol", "rosbridge", "--port", "0"]
        peer = Peer([*argv, "--address", "127.0.0.1", "--quiet", "--format", "json"], self.env)
        try:
            try:
                line = peer.expect(lambda s: '"listening"' in s, START_TIMEOUT)
            except RuntimeError as e:  # before --protocol landed: usage error, exit 2
                yield f"rostools bridge did not start: {str(e)[-200:]}"
                return
            yield Server(str(json.loads(line)["url"]), peer.proc.pid, peer)
        finally:
            peer.stop()

    def measure(self, argv: list[str], server: Server | None) -> Seen:
        """One reader's window; the server's CPU over it."""
        reader = Peer(argv, self.env, stdin=True)
        try:
            try:
                reader.expect(lambda s: s == "ready", FIRST_TIMEOUT)
            except RuntimeError as e:
                return Seen(None, f"no message in {FIRST_TIMEOUT:g} s ({str(e)[-160:]})")
            t0 = time.time_ns() + int(WARMUP * 1e9)
            t1 = t0 + int(WINDOW * 1e9)
            reader.tell(f"{t0} {t1}")
            time.sleep(max(t0 - time.time_ns(), 0) / 1e9)
            cpu0 = cpu_seconds(server.pid) if server else 0.0
            mine0 = cpu_seconds(reader.proc.pid)
            time.sleep(max(t1 - time.time_ns(), 0) / 1e9)
            cpu = (cpu_seconds(server.pid) - cpu0) / WINDOW * 100 if server else None
            mine = (cpu_seconds(reader.proc.pid) - mine0) / WINDOW * 100
            load = os.getloadavg()[0]
            out = json.loads(reader.expect(lambda s: s.startswith("{"), 60))
            reader.stop()
            dropped = []
            if server and server.events:
                gone = server.events.expect(lambda s: '"disconnected"' in s, 30)
                dropped = [json.loads(gone)["dropped"]]
        finally:
            reader.stop()
        return Seen(
            Figures(
                [out["bytes"] / WINDOW / MB],
                [out["messages"]],
                [[d / 1e6 for d in out["delays_ns"]]],
                cpu,
                readers_cpu=[mine],
                dropped=dropped,
                duplicates=out["duplicates"],
                load=load,
            )
        )

    def load_results(self, load: Load) -> list[Result]:
        """The ceiling, then each server with each encoding, for one topic."""
        pub = Peer(
            [
                cpp_peer("pub_sensors", PEERS),
                load.topic,
                load.args[0],
                str(load.rate),
                *load.args[1:],
            ],
            self.env,
        )
        try:
            pub.expect(lambda line: line == "ready", START_TIMEOUT)
            direct = self.measure([self.ours_py, SCRIPT, "direct", self.uri, load.topic], None)
            for name, starter in (
                ("rosbridge_server", self.rosbridge_server),
                ("rostools", self.rostools),
            ):
                with starter() as server:
                    for enc in ENCODINGS:
                        if isinstance(server, str):
                            self.seen[name, enc] = Seen(None, server)
                            continue
                        argv = [sys.executable, SCRIPT, "rosbridge", server.url, load.topic]
                        self.seen[name, enc] = self.measure([*argv, load.type, enc], server)
        finally:
            pub.stop()
        return compare(load, direct, self.seen)


def compare(load: Load, direct: Seen, seen: dict[tuple[str, str], Seen]) -> list[Result]:
    """The goal rows and the delay and CPU rows of one topic."""
    where = f"{load.label} at {load.rate:g} Hz"
    load_avg = max(
        (s.figures.load for s in (direct, *seen.values()) if s.figures), default=os.getloadavg()[0]
    )
    machine = f"load average {load_avg:.1f} on {os.cpu_count()} cores"
    ours_json, theirs_json = seen["rostools", "none"], seen["rosbridge_server", "none"]
    met: bool | None
    if theirs_json.rate == 0:
        met, verdict = ours_json.rate > 0, "; rosbridge_server carried none: no ratio"
    elif theirs_json.rate >= 0.9 * load.rate:
        # both carry what is offered: no ratio above offered / theirs can show
        met, verdict = (
            None,
            (
                f"; rosbridge_server carries the offered {load.rate:g} Hz: no ratio above "
                f"{load.rate / theirs_json.rate:.2f} can show at this load (see the faster load)"
            ),
        )
    else:
        met, verdict = ours_json.rate >= 3 * theirs_json.rate, ""
        if ours_json.rate >= 0.9 * load.rate:
            verdict = "; rostools carries the offered rate: the ratio is a lower bound"
    out = [
        Result(
            f"rosbridge JSON msgs/s, {where}, rostools vs rosbridge_server",
            "msg/s",
            ours_json.rate,
            theirs_json.rate,
            ">= 3x rosbridge_server",
            met,
            f"rostools {ours_json.brief()}; rosbridge_server {theirs_json.brief()}; direct "
            f"{direct.brief()}{verdict}{_cost(ours_json, theirs_json)}; {machine}",
        )
    ]
    for enc in ("cbor-raw", "cbor"):
        ours, theirs = seen["rostools", enc], seen["rosbridge_server", enc]
        out.append(
            Result(
                f"rosbridge {LABEL[enc]} msgs/s, {where}, rostools vs direct TCPROS",
                "msg/s",
                ours.rate,
                direct.rate,
                ">= 0.9x direct",
                ours.rate >= 0.9 * direct.rate if direct.rate else None,
                f"rostools {ours.brief()}; direct {direct.brief()}; rosbridge_server "
                f"{theirs.brief()}; rostools / rosbridge_server {_ratio(ours.rate, theirs.rate)}",
            )
        )
    for enc in ENCODINGS:
        ours, theirs = seen["rostools", enc], seen["rosbridge_server", enc]
        p99 = ours.delay(0.99)
        out.append(
            Result(
                f"rosbridge {LABEL[enc]} delay p99, {where}, rostools vs rosbridge_server",
                "ms",
                p99 if p99 is not None else float("nan"),
                theirs.delay(0.99),
                "report",
                None,
                f"publish (header.stamp) to receive; p50 rostools {_ms(ours.delay(0.5))}, "
                f"rosbridge_server {_ms(theirs.delay(0.5))}, direct {_ms(direct.delay(0.5))} "
                f"(p99 {_ms(direct.delay(0.99))})",
            )
        )
        ours_cpu = ours.figures.cpu if ours.figures and ours.figures.cpu is not None else 0.0
        theirs_cpu = theirs.figures.cpu if theirs.figures else None
        out.append(
            Result(
                f"rosbridge {LABEL[enc]} CPU, {where}, rostools vs rosbridge_server",
                "% core",
                ours_cpu,
                theirs_cpu,
                "report",
                None,
                f"the server process over the window (user + system, all threads), at "
                f"{ours.rate:.1f} and {theirs.rate:.1f} msg/s; CPU ms a message "
                f"{_each(ours)} and {_each(theirs)}; the reader's CPU "
                f"{_reader_cpu(ours)} and {_reader_cpu(theirs)}",
            )
        )
    return out


def _ratio(a: float, b: float) -> str:
    return f"{a / b:.2f}x" if b else "no ratio"


def _ms(value: float | None) -> str:
    return "-" if value is None else f"{value:.1f} ms"


def _cost(ours: Seen, theirs: Seen) -> str:
    a, b = ours.cpu_per_message, theirs.cpu_per_message
    return f"; rosbridge_server spends {b / a:.2f}x our CPU a message" if a and b else ""


def _each(seen: Seen) -> str:
    each = seen.cpu_per_message
    return "-" if each is None else f"{each:.2f}"


def _reader_cpu(seen: Seen) -> str:
    return f"{seen.figures.readers_cpu[0]:.0f}%" if seen.figures else "-"


def bench_throughput() -> list[Result]:
    """Images, then point clouds, through each server in each encoding."""
    # rosbridge's extracted source and generated classes are kept there between runs
    home = BENCH_VENV.parent / "build" / "rosbridge_home"
    with master() as uri:
        run = Run(uri, ros_env(uri), home, str(BENCH_VENV / "bin" / "python"))
        rostools_cmd()  # the benchmark install, before the first server starts
        return [r for load in (IMAGE, IMAGE_FAST, CLOUD) for r in run.load_results(load)]


BENCHMARKS = {"rosbridge_throughput": bench_throughput}
