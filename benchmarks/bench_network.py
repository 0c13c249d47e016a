"""Across hosts and through faults: a master restart, and the first message across hosts.

- ``restart_reregister``: a rostools publisher and a rospy one (``rostopic pub``) run; the
  master is SIGKILLed and started again on the same port. Seconds from the new master's first
  answer until it lists each publisher again (rosmaster and rostools core, in turn).
- ``first_message_across_hosts``: three hosts in network namespaces (needs root), roscore on
  one, a rospy talker on another; on the third, ``rostools topic echo -n 1`` beside
  ``rostopic echo -n 1``, whole process, alternating, median of 5.
"""

from __future__ import annotations

import os
import signal
import statistics
import subprocess
import sys
import time
import xmlrpc.client

from benchmarks.common import (
    SYSTEM_PYTHON,
    Result,
    free_port,
    have,
    ros_env,
    rostools_cmd,
    start,
    stop,
    wait_master,
)

#: How long we wait for a publisher to come back before calling it never.
NEVER = 10.0
ROUNDS = 5


def _publishers(proxy: xmlrpc.client.ServerProxy, topic: str) -> list[str]:
    try:
        _, _, (pubs, _, _) = proxy.getSystemState("/bench")
    except OSError:
        return []
    return next((names for t, names in pubs if t == topic), [])


def _restart_once(kind: str) -> tuple[float | None, float | None]:
    """Seconds until (ours, theirs) are listed again after a restart; None: not in NEVER s."""
    port = free_port()
    uri = f"http://127.0.0.1:{port}/"
    env = ros_env(uri)
    argv = (
        ["rosmaster", "--core", "-p", str(port)]
        if kind == "rosmaster"
        else [*rostools_cmd(), "core", "-p", str(port)]
    )
    quiet = {"stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
    master = start(argv, env, **quiet)
    wait_master(uri)
    ours = start([*rostools_cmd(), "topic", "pub", "-r", "10", "/ours", "std_msgs/String",
                  "data: x"], env, **quiet)  # fmt: skip
    theirs = start(["rostopic", "pub", "-r", "10", "/theirs", "std_msgs/String", "data: x"],
                   env, **quiet)  # fmt: skip
    proxy = xmlrpc.client.ServerProxy(uri)
    try:
        deadline = time.monotonic() + 20
        while not (_publishers(proxy, "/ours") and _publishers(proxy, "/theirs")):
            if time.monotonic() > deadline:
                raise RuntimeError("the publishers did not register")
            time.sleep(0.05)
        os.kill(master.pid, signal.SIGKILL)
        master.wait()
        master = start(argv, env, **quiet)
        wait_master(uri)
        back = time.monotonic()
        seen: dict[str, float] = {}
        while time.monotonic() - back < NEVER and len(seen) < 2:
            for topic in ("/ours", "/theirs"):
                if topic not in seen and _publishers(proxy, topic):
                    seen[topic] = time.monotonic() - back
            time.sleep(0.02)
        return seen.get("/ours"), seen.get("/theirs")
    finally:
        for proc in (ours, theirs, master):
            stop(proc)


def bench_restart_reregister() -> list[Result]:
    """Seconds from a master restart until each publisher is listed again."""
    if not have("rostopic"):
        return []
    results = []
    for kind in ("rosmaster", "rostools core") if have("rosmaster") else ("rostools core",):
        times = [_restart_once(kind.split()[0]) for _ in range(3)]
        ours = [t for t, _ in times if t is not None]
        back = [t for _, t in times if t is not None]
        value = statistics.median(ours) if len(ours) == len(times) else NEVER
        results.append(
            Result(
                f"restart_reregister[{kind}]",
                "s",
                value,
                statistics.median(back) if back else None,
                "<= 2 s (ROS 1: never)",
                value <= 2.0,
                f"median of {len(times)}; rostopic pub back in {len(back)} of {len(times)} "
                f"within {NEVER:g} s",
            )
        )
    return results


def bench_first_message_across_hosts() -> list[Result]:
    """Whole-process time to the first message, subscriber and publisher on two hosts."""
    from tests.support.netlab import Lab, missing
    from tests.support.procs import NODES

    if (reason := missing()) or not have("roscore"):
        print(f"  skipped: {reason or 'no roscore'}", file=sys.stderr)
        return []
    port = free_port()
    with Lab(["robot", "hostb", "hostc"]) as lab:
        env = ros_env(f"http://robot:{port}")
        del env["ROS_IP"]  # each host gives out its own name, as a robot's hosts do
        lab["robot"].start(["roscore", "-p", str(port)], env)
        deadline = time.monotonic() + 30
        while lab["hostc"].run(["rosparam", "get", "/rosdistro"], env).returncode != 0:
            if time.monotonic() > deadline:
                raise RuntimeError("roscore did not start")
            time.sleep(0.3)
        lab["hostb"].start([SYSTEM_PYTHON, str(NODES / "talker.py"), "/chatter", "100"], env)
        commands = {
            "ours": [*rostools_cmd(), "topic", "echo", "/chatter", "-n", "1"],
            "theirs": ["rostopic", "echo", "-n", "1", "/chatter"],
        }
        lab["hostc"].run(commands["theirs"], env, timeout=60)  # the talker is up
        times: dict[str, list[float]] = {"ours": [], "theirs": []}
        for _ in range(ROUNDS):
            for who, argv in commands.items():
                began = time.perf_counter()
                done = lab["hostc"].run(argv, env, timeout=60)
                if done.returncode != 0:
                    raise RuntimeError(f"{argv[0]} failed: {done.stderr[-500:]}")
                times[who].append(time.perf_counter() - began)
    ours, theirs = statistics.median(times["ours"]), statistics.median(times["theirs"])
    return [
        Result(
            "first_message_across_hosts",
            "s",
            ours,
            theirs,
            "< 1x rostopic",
            ours < theirs,
            f"talker on one host, echo -n 1 on another, roscore on a third; median of {ROUNDS}",
        )
    ]


BENCHMARKS = {
    "restart_reregister": bench_restart_reregister,
    "first_message_across_hosts": bench_first_message_across_hosts,
}
