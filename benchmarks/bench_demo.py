"""``rostools demo`` from start to end, beside the same session typed with ROS 1's tools.

Ours: ``rostools demo`` in a fresh folder, launch to exit (its master, talker and service
start in-process; every step is a command of its own; its teardown is counted). Theirs:
``roscore``, a rospy talker at 10 Hz and a rospy service server, then ``rostopic list``,
``rostopic echo -n 3``, ``rostopic hz`` for 1.3 s, ``rosservice call /trigger``
(rospy_tutorials' AddTwoInts is not packaged by Debian), ``rosparam get``, ``rosbag record
--duration 3`` (started first and run beside the steps before it, as the demo does) and
``rosbag info``: launch until the last step has ended (their teardown is not counted).
Each is timed on a quiet machine and with ``BUSY`` processes spinning on the CPU; the goal is
the README's, under ten seconds.
"""

from __future__ import annotations

import os
import statistics
import subprocess
import tempfile
import time
from collections.abc import Callable

from benchmarks.bench_load_busy import busy
from benchmarks.common import ROOT, Result, free_port, have, ros_env, rostools_cmd, start, stop

#: Runs of each, the median reported.
RUNS = 3
#: Processes spinning on the CPU in the loaded rounds: two per core.
BUSY = 2 * (os.cpu_count() or 1)
#: The README's promise (s).
GOAL = 10.0
NODES = ROOT / "tests" / "support" / "ros1_nodes"
SYSTEM_PYTHON = "/usr/bin/python3"


def _ours() -> float:
    with tempfile.TemporaryDirectory() as tmp:
        began = time.perf_counter()
        subprocess.run(
            [*rostools_cmd(), "demo"], cwd=tmp, env=ros_env("http://127.0.0.1:9/"),
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=True, timeout=300,
        )  # fmt: skip
        return time.perf_counter() - began


def _step(argv: list[str], env: dict[str, str], cwd: str, seconds: float | None = None) -> None:
    """One ROS 1 command to its end (or, with ``seconds``, until Ctrl-C after that long)."""
    if seconds is None:
        subprocess.run(argv, env=env, cwd=cwd, stdout=subprocess.DEVNULL, check=True, timeout=120)
        return
    proc = start(argv, env, cwd=cwd, stdout=subprocess.DEVNULL)
    time.sleep(seconds)  # rostopic hz has no --timeout: the demo's 1.3 s, then Ctrl-C
    stop(proc)


def _theirs() -> float:
    port = free_port()
    uri = f"http://127.0.0.1:{port}/"
    env = ros_env(uri)
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
    with tempfile.TemporaryDirectory() as tmp:
        began = time.perf_counter()
        procs = [start(["roscore", "-p", str(port)], env, **quiet)]
        try:
            _wait_for(lambda: _topic_listed(env, "/rosout"), "roscore")
            procs.append(
                start([SYSTEM_PYTHON, str(NODES / "talker.py"), "/chatter", "10"], env, **quiet)
            )
            procs.append(
                start([SYSTEM_PYTHON, str(NODES / "add_two_ints_server.py")], env, **quiet)
            )
            _step(["rosparam", "set", "/demo", "{robot_name: demo_bot, max_speed: 0.5}"], env, tmp)
            _wait_for(lambda: _service_listed(env, "/trigger"), "the service")
            record = start(
                ["rosbag", "record", "/chatter", "-O", "demo.bag", "--duration", "3"],
                env, cwd=tmp, **quiet,
            )  # fmt: skip
            procs.append(record)
            _step(["rostopic", "list"], env, tmp)
            _step(["rostopic", "echo", "-n", "3", "/chatter"], env, tmp)
            _step(["rostopic", "hz", "/chatter"], env, tmp, seconds=1.3)
            _step(["rosservice", "call", "/trigger"], env, tmp)
            _step(["rosparam", "get", "/demo"], env, tmp)
            record.wait(120)
            _step(["rosbag", "info", "demo.bag"], env, tmp)
            return time.perf_counter() - began
        finally:
            for proc in reversed(procs):
                stop(proc)


def _topic_listed(env: dict[str, str], topic: str) -> bool:
    done = subprocess.run(["rostopic", "list"], env=env, capture_output=True, text=True)
    return topic in done.stdout.split()


def _service_listed(env: dict[str, str], service: str) -> bool:
    done = subprocess.run(["rosservice", "list"], env=env, capture_output=True, text=True)
    return service in done.stdout.split()


def _wait_for(ready: Callable[[], bool], what: str, timeout: float = 60.0) -> None:
    deadline = time.monotonic() + timeout
    while not ready():
        if time.monotonic() > deadline:
            raise RuntimeError(f"{what} did not come up")
        time.sleep(0.05)


def _median(session: Callable[[], float]) -> float:
    return statistics.median(session() for _ in range(RUNS))


def bench_demo() -> list[Result]:
    results = []
    for label, load in (("quiet", 0), (f"{BUSY} processes spinning", BUSY)):
        with busy(load):
            ours = _median(_ours)
            theirs = _median(_theirs) if have("roscore") else None
        results.append(
            Result(
                f"demo session, {label}",
                "s",
                ours,
                theirs,
                f"< {GOAL:g} s",
                ours < GOAL,
                f"rostools demo, launch to exit; ROS 1: the same steps with roscore, rospy nodes"
                f" and the rostopic/rosservice/rosparam/rosbag tools; median of {RUNS}",
            )
        )
    return results


BENCHMARKS = {"demo": bench_demo}
