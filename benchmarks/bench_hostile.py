"""The master's other clients under hostile load, beside the real rosmaster in one run.

A probe calls ``getPid`` every 5 ms on its own keep-alive connection and records each call's
latency while attackers run: two clients looping on a 681-byte billion-laughs body, one
client looping on 60 MiB ``setParam`` bodies, or six clients trickling 63 MiB bodies. Every
client is ``hostile_client.py`` on the system python, the same for both masters; the masters
take turns, so only one is under load at a time.
"""

from __future__ import annotations

import statistics
import subprocess
import time
from pathlib import Path

from benchmarks.common import (
    SYSTEM_PYTHON,
    Result,
    free_port,
    masters,
    ros_env,
    start,
    stop,
    wait_master,
)

CLIENT = Path(__file__).with_name("hostile_client.py")
#: (name, attackers, seconds the probe runs); attackers are (mode, count, seconds each).
SCENARIOS: list[tuple[str, list[tuple[str, int, float]], float]] = [
    ("no load", [], 3.0),
    ("entity flood (2 clients)", [("entity", 2, 6.0)], 6.0),
    ("60 MiB setParam bodies", [("bigparam", 1, 8.0)], 8.0),
    ("six slow 63 MiB bodies", [("slowbody", 6, 5.0)], 9.0),
]


def _client(port: int, seconds: float, mode: str) -> subprocess.Popen[str]:
    return subprocess.Popen(
        [SYSTEM_PYTHON, str(CLIENT), str(port), str(seconds), mode],
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
    )


def _latencies(port: int, attackers: list[tuple[str, int, float]], seconds: float) -> list[float]:
    """The probe's latencies in ms while the attackers run."""
    attacking = [_client(port, each, mode) for mode, count, each in attackers for _ in range(count)]
    time.sleep(0.3)  # the attack is under way before the probe starts
    probe = _client(port, seconds, "probe")
    out, _ = probe.communicate(timeout=seconds + 120)
    for proc in attacking:
        try:
            proc.communicate(timeout=120)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
    return [float(line) for line in out.split()]


def _percentile(samples: list[float], share: float) -> float:
    ordered = sorted(samples)
    return ordered[min(len(ordered) - 1, int(share * len(ordered)))]


def bench_master_hostile() -> list[Result]:
    found: dict[tuple[str, str], list[float]] = {}
    for name, argv in masters().items():
        port = free_port()
        uri = f"http://127.0.0.1:{port}/"
        proc = start(
            [*argv, str(port)],
            ros_env(uri),
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        try:
            wait_master(uri)
            for scenario, attackers, seconds in SCENARIOS:
                found[(name, scenario)] = _latencies(port, attackers, seconds)
        finally:
            stop(proc)
    results = []
    for scenario, _, _ in SCENARIOS:
        ours = found[("ours", scenario)]
        theirs = found.get(("theirs", scenario))
        for label, share in (("p50", 0.5), ("p99", 0.99)):
            mine = _percentile(ours, share)
            other = _percentile(theirs, share) if theirs else None
            met = None if other is None or label == "p50" else mine <= max(other, 10.0)
            results.append(
                Result(
                    f"master getPid latency {label}, {scenario}",
                    "ms",
                    mine,
                    other,
                    "p99 <= rosmaster's (or 10 ms)" if label == "p99" else "report",
                    met,
                    f"{len(ours)} probe calls (rosmaster: {len(theirs or [])}); max "
                    f"{max(ours):.1f} ms (rosmaster: {max(theirs or [0]):.1f} ms); median "
                    f"{statistics.median(ours):.2f} ms",
                )
            )
    return results


BENCHMARKS = {"master_hostile": bench_master_hostile}
