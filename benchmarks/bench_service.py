"""Services: one call as a whole process, and calls per second over a persistent client."""

from __future__ import annotations

import json
import statistics
import subprocess
import time
from pathlib import Path

from benchmarks.common import (
    BENCH_VENV,
    SYSTEM_PYTHON,
    Result,
    have,
    master,
    ros_env,
    rostools_cmd,
    start,
    stop,
    time_commands,
)

ROOT = Path(__file__).resolve().parent.parent
SERVER = ROOT / "tests" / "support" / "ros1_nodes" / "add_two_ints_server.py"
PEERS = Path(__file__).with_name("peers")
SECONDS = 4.0
#: Rounds of each client, in turns.
ROUNDS = 3


def _with_rospy_server(fn):  # type: ignore[no-untyped-def]
    with master() as uri:
        env = ros_env(uri)
        server = start(
            [SYSTEM_PYTHON, str(SERVER)], env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
        )
        try:
            time.sleep(3.0)  # rospy registers services in the background
            return fn(uri, env)
        finally:
            stop(server)


def bench_service_call_process() -> Result:
    if not have("rosservice"):
        return Result(
            "service call (wall, whole process)", "ms", 0.0, None, "report", None, "no ROS 1"
        )

    def run(uri: str, env: dict[str, str]) -> dict[str, float]:
        return time_commands(
            {
                "ours": [*rostools_cmd(), "service", "call", "/trigger"],
                "theirs": ["rosservice", "call", "/trigger"],
            },
            runs=20,
            env=env,
        )

    t = _with_rospy_server(run)
    return Result(
        "service call /trigger (wall, whole process)",
        "ms",
        t["ours"] * 1e3,
        t["theirs"] * 1e3,
        "report (faster is better)",
        t["ours"] < t["theirs"],
        "same rospy std_srvs/Trigger server",
    )


def bench_service_calls_persistent() -> list[Result]:
    if not have("rosservice"):
        return [
            Result("persistent service calls", "calls/s", 0.0, None, "report", None, "no ROS 1")
        ]

    def rate(argv: list[str], env: dict[str, str]) -> float:
        out = subprocess.run(argv, env=env, capture_output=True, text=True, timeout=60, check=True)
        data = json.loads(out.stdout)
        return float(data["calls"]) / float(data["seconds"])

    def run(uri: str, env: dict[str, str]) -> tuple[float, float, float]:
        ours = [
            str(BENCH_VENV / "bin" / "python"),
            str(PEERS / "rt_service_calls.py"),
            uri,
            str(SECONDS),
        ]
        theirs = [SYSTEM_PYTHON, str(PEERS / "rospy_service_calls.py"), str(SECONDS)]
        samples: dict[str, list[float]] = {"blocking": [], "async": [], "rospy": []}
        # In turns, ROUNDS times: the machine is shared and its load drifts.
        for _ in range(ROUNDS):
            samples["blocking"].append(rate([*ours, "blocking"], env))
            samples["async"].append(rate([*ours, "async"], env))
            samples["rospy"].append(rate(theirs, env))
        blocking, asynchronous, rospy = (
            statistics.median(samples[k]) for k in ("blocking", "async", "rospy")
        )
        return blocking, asynchronous, rospy

    rostools_cmd()
    blocking, asynchronous, theirs = _with_rospy_server(run)
    note = (
        "vs a persistent rospy ServiceProxy, same rospy Trigger server;"
        f" median of {ROUNDS} rounds in turns"
    )
    return [
        Result(
            "persistent BlockingServiceClient calls",
            "calls/s",
            blocking,
            theirs,
            "report (more is better)",
            blocking > theirs,
            note,
        ),
        Result(
            "persistent asyncio ServiceClient calls",
            "calls/s",
            asynchronous,
            theirs,
            "report (more is better)",
            asynchronous > theirs,
            f"{note}; {asynchronous / blocking:.2f}x the blocking client",
        ),
    ]


BENCHMARKS = {
    "service_call_process": bench_service_call_process,
    "service_calls_persistent": bench_service_calls_persistent,
}
