"""A master killed outright and started again under running nodes, on both masters.

rospy and roscpp never register again, so after a respawn they are invisible to everyone who
starts later. Ours (pub, echo, record, play) notice the new master and register again, and
carry on.
"""

from __future__ import annotations

import json
import os
import signal
import sys
import time
import xmlrpc.client
from pathlib import Path

import pytest

from tests.support.bagdata import write_play_bag
from tests.support.env import needs_ros1, run_cli
from tests.support.procs import (
    Proc,
    free_port,
    master_answers,
    ros_env,
    start_ros1_node,
    start_roscore,
    start_rostools_core,
    wait_for,
)

pytestmark = [pytest.mark.interop, needs_ros1]


def listed(topic: str, env: dict[str, str]) -> bool:
    return topic in run_cli("topic", "list", env=env).stdout.split()


def registered(master: str, topic: str, kind: int = 0) -> list[str]:
    """The publishers (``kind`` 0) or subscribers (1) of ``topic`` the master lists."""
    state = xmlrpc.client.ServerProxy(master).getSystemState("/t")[2][kind]
    return next((names for t, names in state if t == topic), [])


def kill_master(master: Proc, uri: str) -> None:
    """SIGKILL the master and its /rosout, by PID: roslaunch puts them in sessions of their own."""
    proxy = xmlrpc.client.ServerProxy(uri)
    pids = {int(proxy.getPid("/t")[2]), master.pid}
    code, _, rosout = proxy.lookupNode("/t", "/rosout")
    if code == 1:
        pids.add(int(xmlrpc.client.ServerProxy(rosout).getPid("/t")[2]))
    for pid in pids:
        os.kill(pid, signal.SIGKILL)
    master.stop()
    wait_for(lambda: not master_answers(uri), 10, "the master gone")


@pytest.mark.parametrize("kind", ["rostools", "roscore"])
def test_nodes_carry_on_through_a_master_restart(
    kind: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    port = free_port()
    uri = f"http://127.0.0.1:{port}"
    cli_env["ROS_MASTER_URI"] = uri
    env = ros_env(uri, tmp_path / "ros_home")

    def start_master() -> Proc:
        return (
            start_rostools_core(port, cli_env) if kind == "rostools" else start_roscore(port, env)
        )

    rostools = [sys.executable, "-m", "rostools"]
    master = start_master()
    procs: list[Proc] = []
    try:
        procs.append(Proc([*rostools, "topic", "pub", "-r", "10", "/kept", "std_msgs/String",
                           "data: kept"], env=cli_env))  # fmt: skip
        talker = start_ros1_node("talker.py", ["/spoken", "20"], env)
        procs.append(talker)
        echo = Proc([*rostools, "topic", "echo", "/spoken", "-F", "json"], env=cli_env)
        procs.append(echo)
        write_play_bag(tmp_path / "loop.bag")
        procs.append(Proc([*rostools, "bag", "play", "-l", str(tmp_path / "loop.bag"),
                           "/chatter:=/replayed"], env=cli_env))  # fmt: skip
        bag = tmp_path / "through.bag"
        record = Proc([*rostools, "bag", "record", "-a", "-O", str(bag)], env=cli_env)
        procs.append(record)
        wait_for(lambda: listed("/kept", cli_env) and listed("/spoken", cli_env), 20, "graph")
        echo.expect("hello", 15)
        wait_for(lambda: any("record" in n for n in registered(uri, "/spoken", 1)), 10, "recording")

        kill_master(master, uri)
        master = start_master()
        restarted = time.monotonic()
        wait_for(lambda: listed("/kept", cli_env), 5, "/kept registered again")
        back_after = time.monotonic() - restarted
        # the rospy talker never registers again: the new master knows no publisher of /spoken
        assert registered(uri, "/spoken") == []

        # a subscriber that starts now hears the publisher that started before
        listener = start_ros1_node("listener.py", ["/kept"], env)
        procs.append(listener)
        listener.expect("got kept", 20)
        # and one that starts now hears the player that started before
        replayed = start_ros1_node("listener.py", ["/replayed"], env)
        procs.append(replayed)
        replayed.expect("got m", 20)
        # a publisher that starts now is recorded by the recorder that started before
        # (named apart: a second /talker would make the new master shut one down)
        procs.append(
            start_ros1_node("talker.py", ["/later", "20", "0", "-1", "__name:=later"], env)
        )
        # and the echo that started before still hears the talker that did too
        for _ in range(5):
            assert json.loads(echo.expect("hello", 10))["data"].startswith("hello")
        # the recorder asks the master every second; then the talker has 20 messages a second
        wait_for(lambda: any("record" in n for n in registered(uri, "/later", 1)), 20, "/later")
        time.sleep(1.0)
        record.signal(signal.SIGINT)
        assert record.popen.wait(15) == 0
        info = json.loads(run_cli("bag", "info", str(bag), "-F", "json", env=cli_env).stdout)
        counts = {t["topic"]: t["messages"] for t in info["topics"]}
        assert {"/kept", "/spoken", "/later"} <= counts.keys(), counts
        assert back_after < 3.0, f"registered again {back_after:.2f} s after the restart"
    finally:
        for proc in procs:
            proc.stop()
        master.stop()


def test_a_roscore_stopped_the_hard_way_leaves_no_master_behind(tmp_path: Path) -> None:
    # The fixtures' roscore: when it had to be SIGKILLed, its rosmaster (in a process group of
    # its own) went on running, and a later run found a stray master.
    port = free_port()
    uri = f"http://127.0.0.1:{port}/"
    core = start_roscore(port, ros_env(uri, tmp_path / "ros_home"))
    master_pid = int(xmlrpc.client.ServerProxy(uri).getPid("/t")[2])
    core.stop()  # no time to shut down: SIGKILL reaches roscore before its children

    def gone() -> bool:  # a zombie counts as gone: this container's PID 1 may never reap it
        try:
            return Path(f"/proc/{master_pid}/stat").read_text().rsplit(")", 1)[1].split()[0] in "ZX"
        except OSError:
            return True

    wait_for(gone, 10, "the master gone")
