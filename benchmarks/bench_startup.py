"""Cold start of every command that only asks the master, beside its ROS 1 tool (issue 14).

Set-up, as the independent harness had it: the real rosmaster as a neutral master, a few
parameters, 50 publishers registered (fake nodes, registered over XML-RPC), and one rospy
talker (a real node, for ``node info`` and ``service type``, which ask it). Each command is a
whole process, timed wall to wall; ours and theirs alternate, median of ``RUNS``.
"""

from __future__ import annotations

import os
import subprocess
import sys
import time
import xmlrpc.client
from pathlib import Path

from benchmarks.common import (
    ROOT,
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

RUNS = 15
PUBLISHERS = 50
GOAL = 0.5

#: (our arguments, the ROS 1 command): every command that only asks the master or a node.
COMMANDS: list[tuple[list[str], list[str]]] = [
    (["param", "get", "/a"], ["rosparam", "get", "/a"]),
    (["param", "list"], ["rosparam", "list"]),
    (["topic", "list"], ["rostopic", "list"]),
    (["topic", "info", "/chatter"], ["rostopic", "info", "/chatter"]),
    (["topic", "type", "/chatter"], ["rostopic", "type", "/chatter"]),
    (["topic", "find", "std_msgs/String"], ["rostopic", "find", "std_msgs/String"]),
    (["service", "list"], ["rosservice", "list"]),
    (["service", "type", "/talker/get_loggers"], ["rosservice", "type", "/talker/get_loggers"]),
    (["service", "uri", "/talker/get_loggers"], ["rosservice", "uri", "/talker/get_loggers"]),
    (["node", "list"], ["rosnode", "list"]),
    (["node", "info", "/talker", "-q"], ["rosnode", "info", "/talker", "-q"]),
]


def _populate(uri: str) -> None:
    """A few parameters and PUBLISHERS publishers, one fake node each."""
    master_proxy = xmlrpc.client.ServerProxy(uri)
    for name, value in (("/a", 1), ("/b", "text"), ("/c/d", [1.5, 2.5]), ("/c/e", True)):
        master_proxy.setParam("/bench", name, value)
    for i in range(PUBLISHERS):
        node = f"/fake_{i}"
        master_proxy.registerPublisher(
            node, f"/fake/topic_{i}", "std_msgs/String", f"http://127.0.0.1:{40000 + i}/"
        )


def bench_startup() -> list[Result]:
    """Median whole-process wall time of each command, ours and the ROS 1 tool's."""
    rostools = rostools_cmd()
    results: list[Result] = []
    with master() as uri:
        env = ros_env(uri)
        _populate(uri)
        talker = start(
            [SYSTEM_PYTHON, str(ROOT / "tests/support/ros1_nodes/talker.py"), "/chatter", "5"],
            env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        try:
            time.sleep(2.0)  # the talker registers
            for ours, theirs in COMMANDS:
                commands = {"ours": [*rostools, *ours]}
                if have(theirs[0]):
                    commands["theirs"] = theirs
                t = time_commands(commands, runs=RUNS, warmup=2, env=env)
                mine, ros1 = t["ours"] * 1e3, t.get("theirs")
                results.append(
                    Result(
                        f"{' '.join(ours[:2])} cold start (wall, whole process)",
                        "ms",
                        mine,
                        None if ros1 is None else ros1 * 1e3,
                        f"<= {GOAL}x {theirs[0]}",
                        None if ros1 is None else mine <= GOAL * ros1 * 1e3,
                        f"{' '.join(theirs)}; rosmaster, {PUBLISHERS} publishers, median of {RUNS}",
                    )
                )
            results.append(_launcher_row(rostools, env))
        finally:
            stop(talker)
    return results


def _launcher_row(rostools: list[str], env: dict[str, str]) -> Result:
    """``param get`` through the launcher beside the same command through Typer.

    Why the quick commands have a launcher of their own: ``ROSTOOLS_NO_QUICK=1`` sends the
    same command line to Typer, which runs the same function. Both start through ``env``.
    """
    command = ["param", "get", "/a"]
    t = time_commands(
        {
            "ours": ["env", *rostools, *command],
            "theirs": ["env", "ROSTOOLS_NO_QUICK=1", *rostools, *command],
        },
        runs=RUNS,
        warmup=2,
        env=env,
    )
    return Result(
        "param get cold start: the launcher, vs the same command through Typer",
        "ms",
        t["ours"] * 1e3,
        t["theirs"] * 1e3,
        "faster than Typer",
        t["ours"] < t["theirs"],
        f"ROSTOOLS_NO_QUICK=1 for Typer; rosmaster, median of {RUNS}",
    )


#: The quick path's commands: a change that only moves code must leave their start-up alone.
QUICK = [["topic", "list"], ["param", "get", "/a"], ["msg", "md5", "std_msgs/String"]]
#: How much slower than before the quick path may start (noise on a shared machine included).
SAME = 1.05


def bench_startup_trees() -> list[Result]:
    """The quick path's cold start in this checkout beside another's, in one run.

    ``ROSTOOLS_BENCH_BEFORE`` names the other checkout (say, main at a branch's start); both
    are installed as users get them, into each checkout's ``benchmarks/.venv``, and their
    runs alternate. ``theirs`` is the other checkout.
    """
    before = os.environ.get("ROSTOOLS_BENCH_BEFORE")
    if not before:
        print("startup_trees: set ROSTOOLS_BENCH_BEFORE to another checkout", file=sys.stderr)
        return []
    after_cmd, before_cmd = rostools_cmd(), rostools_cmd(Path(before))
    results: list[Result] = []
    with master() as uri:
        env = ros_env(uri)
        _populate(uri)
        for command in QUICK:
            t = time_commands(
                {"ours": [*after_cmd, *command], "theirs": [*before_cmd, *command]},
                runs=RUNS,
                warmup=2,
                env=env,
            )
            mine, then = t["ours"] * 1e3, t["theirs"] * 1e3
            results.append(
                Result(
                    f"{' '.join(command[:2])} cold start, this checkout vs the one before",
                    "ms",
                    mine,
                    then,
                    f"<= {SAME}x before",
                    mine <= SAME * then,
                    f"rosmaster, {PUBLISHERS} publishers, median of {RUNS}, runs alternating",
                )
            )
    return results


BENCHMARKS = {"startup": bench_startup, "startup_trees": bench_startup_trees}
