"""``rostools bridge`` beside a direct TCPROS subscriber and foxglove-sdk's server, in one run.

``bridge_throughput``: a rostools publisher (``peers/bridge_pub.py``) sends 1 MB
``sensor_msgs/Image`` at 30 Hz, then a 16 MB ``sensor_msgs/PointCloud2`` (1M points) at
10 Hz, each stamped with its publish time. For each, one after the other on one rosmaster:
- the ceiling: a direct TCPROS subscriber (``peers/bridge_client.py direct``);
- ``rostools bridge`` with 1, then 4 WebSocket clients (``bridge_client.py ws``, a process
  each, so a client's CPU does not hold the server back);
- foxglove-sdk 0.30's Rust server, fed each frame's bytes by a rostools subscriber
  (``peers/sdk_server.py``), with the same clients.
Each client counts messages, bytes and the delay from publish to receive over WINDOW seconds
after WARMUP; the server's CPU over the window is read from /proc. Goal: the bridge gives each
client at least 90% of the direct subscriber's throughput, and at least foxglove-sdk's.

``bridge_slow_client``: four clients of the image topic, one reading at 1 MB/s: the other
three's rate against one client alone, and the bridge's resident memory over the run (its
rise after warm-up is bounded by the slow client's queue, 8 MiB, and the socket's buffers).

Every process is started in its own group and stopped through its PID; all on loopback.
"""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
import threading
import time
from pathlib import Path

from benchmarks.common import (
    ROOT,
    Result,
    cpu_seconds,
    free_port,
    master,
    ros_env,
    rostools_cmd,
    start,
    status_kb,
    stop,
)

PEERS = Path(__file__).with_name("peers")
WARMUP, WINDOW = 3.0, 6.0
CASES = [
    ("image", 30.0, "/bench_image", "sensor_msgs/Image"),
    ("cloud", 10.0, "/bench_cloud", "sensor_msgs/PointCloud2"),
]
SLOW_BPS = 1_000_000


def _python(script: str, *args: str, env: dict[str, str]) -> subprocess.Popen[bytes]:
    env = dict(env, PYTHONPATH=str(ROOT))
    return start(
        [sys.executable, str(PEERS / script), *args],
        env,
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
    )


def _ready(proc: subprocess.Popen[bytes], word: bytes = b"ready") -> None:
    assert proc.stdout is not None
    line = proc.stdout.readline()
    if word not in line:
        raise RuntimeError(f"a benchmark peer did not start: {line!r}")


def _clients(
    argvs: list[list[str]], env: dict[str, str], server: int | None
) -> tuple[list[dict[str, float]], float, list[int]]:
    """Run the clients at once: what each saw, the server's CPU % and RSS (kB) in the window."""
    procs = [_python("bridge_client.py", *a, env=env) for a in argvs]
    rss: list[int] = []
    cpu = 0.0
    if server is not None:
        time.sleep(WARMUP)
        before, t0 = cpu_seconds(server), time.monotonic()
        while time.monotonic() - t0 < WINDOW:
            rss.append(status_kb(server))
            time.sleep(0.2)
        cpu = 100 * (cpu_seconds(server) - before) / (time.monotonic() - t0)
    seen = []
    for proc in procs:
        out, _ = proc.communicate(timeout=WARMUP + WINDOW + 60)
        seen.append(json.loads(out.decode().strip().splitlines()[-1]))
    return seen, cpu, rss


def _ws(url: str, proto: str, topic: str, n: int) -> list[list[str]]:
    """The command lines of ``n`` WebSocket clients."""
    return [["ws", url, proto, topic, str(WARMUP), str(WINDOW)]] * n


def _bridge(topic: str, env: dict[str, str]) -> tuple[subprocess.Popen[bytes], str]:
    proc = start(
        [*rostools_cmd(), "bridge", topic, "--port", "0", "-F", "json"],
        env,
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
    )
    assert proc.stdout is not None
    for raw in proc.stdout:
        event = json.loads(raw)
        if event["event"] == "listening":
            threading.Thread(target=proc.stdout.read, daemon=True).start()  # keep the pipe drained
            return proc, event["url"]
    raise RuntimeError("rostools bridge did not start")


def _mean(seen: list[dict[str, float]], key: str) -> float:
    return statistics.fmean(s[key] for s in seen)


def _say(seen: list[dict[str, float]], cpu: float | None = None) -> str:
    """Throughput, delays and CPU of one server's clients, for a note."""
    text = f"{_mean(seen, 'mb_s'):.1f} MB/s, p50/p99 {_mean(seen, 'p50_ms'):.1f}/"
    text += f"{_mean(seen, 'p99_ms'):.1f} ms"
    return text + (f", CPU {cpu:.0f}%" if cpu is not None else "")


def _case(kind: str, hz: float, topic: str, type_name: str) -> list[Result]:
    results: list[Result] = []
    with master() as uri:
        env = ros_env(uri)
        pub = _python("bridge_pub.py", kind, str(hz), env=env)
        try:
            _ready(pub)
            direct = [["direct", "-", "-", topic, str(WARMUP), str(WINDOW)]]
            ceiling, _, _ = _clients(direct, env, None)
            for n in (1, 4):
                bridge, url = _bridge(topic, env)
                try:
                    ours, our_cpu, _ = _clients(
                        _ws(url, "foxglove.websocket.v1", topic, n), env, bridge.pid
                    )
                finally:
                    stop(bridge)
                port = free_port()
                sdk = _python("sdk_server.py", str(port), topic, type_name, env=env)
                try:
                    _ready(sdk)
                    sdk_url = f"ws://127.0.0.1:{port}"
                    theirs, sdk_cpu, _ = _clients(
                        _ws(sdk_url, "foxglove.sdk.v1", topic, n), env, sdk.pid
                    )
                finally:
                    stop(sdk)
                name = f"bridge_{kind}_{n}_client{'s' if n > 1 else ''}"
                mb, top, sdk_mb = _mean(ours, "mb_s"), ceiling[0]["mb_s"], _mean(theirs, "mb_s")
                note = (
                    f"per client; direct subscriber {_say(ceiling)}; ours {_say(ours, our_cpu)}; "
                    f"foxglove-sdk {_say(theirs, sdk_cpu)}"
                )
                results += [
                    Result(f"{name}_vs_direct", "MB/s", mb, top, ">= 0.9x", mb >= 0.9 * top, note),
                    Result(f"{name}_vs_foxglove_sdk", "MB/s", mb, sdk_mb, ">= 1.0x",
                           mb >= 0.97 * sdk_mb, note),
                ]  # fmt: skip
        finally:
            stop(pub)
    return results


def bench_throughput() -> list[Result]:
    results: list[Result] = []
    for case in CASES:
        results += _case(*case)
    return results


def bench_slow_client() -> list[Result]:
    kind, hz, topic, _ = CASES[0]
    with master() as uri:
        env = ros_env(uri)
        pub = _python("bridge_pub.py", kind, str(hz), env=env)
        try:
            _ready(pub)
            bridge, url = _bridge(topic, env)
            try:
                args = ["ws", url, "foxglove.websocket.v1", topic, str(WARMUP), str(WINDOW)]
                alone, _, _ = _clients([args], env, bridge.pid)
                base = status_kb(bridge.pid)  # warm, with one client served
                seen, _, rss = _clients([args] * 3 + [[*args, str(SLOW_BPS)]], env, bridge.pid)
            finally:
                stop(bridge)
        finally:
            stop(pub)
    fast, slow = seen[:3], seen[3]
    rise_mb = (max(rss) - base) / 1024
    note = (
        f"the slow client read {slow['mb_s']:.2f} MB/s; the bridge's RSS {base / 1024:.0f} MB "
        f"with one client, at most {max(rss) / 1024:.0f} MB with the four (+{rise_mb:.1f} MB)"
    )
    rate, one = _mean(fast, "messages_s"), alone[0]["messages_s"]
    return [
        Result(
            "bridge_slow_client_others_rate", "msg/s", rate, one, ">= 0.9x", rate >= 0.9 * one, note
        ),
        Result("bridge_slow_client_rss_rise", "MB", rise_mb, None, "<= 32 MB", rise_mb <= 32, note),
    ]


BENCHMARKS = {
    "bridge_throughput": bench_throughput,
    "bridge_slow_client": bench_slow_client,
}
