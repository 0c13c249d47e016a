"""A master killed outright and started again under running nodes, on both masters.

rospy and roscpp never register again what they registered before, so after a respawn that
is invisible to everyone who starts later (what docs/networking.md says of them is checked here on
roscore). Ours (pub, echo, record, play) notice the new master and register again, and
carry on.
"""

from __future__ import annotations

import json
import os
import signal
import time
import xmlrpc.client
from pathlib import Path

import pytest

from rostools.bag.formats.access import open_bag
from tests.support.bagdata import recorded, write_play_bag
from tests.support.env import ROOT, needs_ros1, run_cli
from tests.support.procs import (
    Proc,
    free_port,
    master_answers,
    publishers,
    ros_env,
    start_cli,
    start_ros1_node,
    start_roscore,
    start_rostools_core,
    subscribers,
    wait_for,
)

pytestmark = [pytest.mark.interop, needs_ros1]


def listed(topic: str, env: dict[str, str]) -> bool:
    return topic in run_cli("topic", "list", env=env).stdout.split()


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

    master = start_master()
    procs: list[Proc] = []
    try:
        procs.append(
            start_cli(
                "topic", "pub", "-r", "10", "/kept", "std_msgs/String", "data: kept", env=cli_env
            )
        )
        talker = start_ros1_node("talker.py", ["/spoken", "20"], env)
        procs.append(talker)
        echo = start_cli("topic", "echo", "/spoken", "-F", "json", env=cli_env)
        procs.append(echo)
        write_play_bag(tmp_path / "loop.bag")
        loop = str(tmp_path / "loop.bag")
        procs.append(start_cli("bag", "play", "-l", loop, "/chatter:=/replayed", env=cli_env))
        bag = tmp_path / "through.bag"
        record = start_cli("bag", "record", "-a", "-O", str(bag), env=cli_env)
        procs.append(record)
        wait_for(lambda: listed("/kept", cli_env) and listed("/spoken", cli_env), 20, "graph")
        echo.expect("hello", 15)
        wait_for(lambda: any("record" in n for n in subscribers(uri, "/spoken")), 10, "recording")

        kill_master(master, uri)
        master = start_master()
        restarted = time.monotonic()
        wait_for(lambda: listed("/kept", cli_env), 5, "/kept registered again")
        back_after = time.monotonic() - restarted
        # the rospy talker never registers again: the new master knows no publisher of /spoken
        assert publishers(uri, "/spoken") == []

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
        active = bag.with_name(f"{bag.name}.active")
        wait_for(lambda: recorded(active, "/later"), 20, "/later recorded", 0.2)
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


#: The claim of docs/networking.md (its lines joined) that the next test checks.
DOCS_CLAIM = (
    "rospy and roscpp nodes never register again what they registered before; only what they"
    " register afterwards reaches the new master. So a subscriber that starts later cannot find"
    " an earlier publisher, and an earlier subscriber hears no later publisher: `rosbag record"
    " TOPIC` records nothing more, and `rosbag record -a`, which asks the master every second,"
    " records the topics new to it but misses later publishers of the topics it was recording"
    " already"
)


def test_ros1_nodes_register_nothing_again_after_a_restart(tmp_path: Path) -> None:
    """What docs/networking.md says of rospy and roscpp under a restarted roscore (ros_comm 1.15).

    Neither registers again anything it registered before. What a node registers afterwards
    goes to the new master as usual: ``rosbag record -a`` (roscpp) asks the master every
    second and subscribes to topics new to it, so it records their later publishers, but not
    the later publishers of a topic it was recording already. ``rosbag record TOPIC`` and a
    rospy subscriber hear no later publisher at all.
    """
    page = " ".join((ROOT / "docs" / "networking.md").read_text().split())
    assert DOCS_CLAIM in page, "docs/networking.md no longer says what this test checks"
    port = free_port()
    uri = f"http://127.0.0.1:{port}"
    env = ros_env(uri, tmp_path / "ros_home")
    master = start_roscore(port, env)
    procs: list[Proc] = []

    def talker(topic: str, name: str) -> Proc:
        proc = start_ros1_node("talker.py", [topic, "20", "0", "-1", f"__name:={name}"], env)
        procs.append(proc)
        return proc

    def subs(topic: str) -> list[str]:
        return sorted(subscribers(uri, topic))

    try:
        talker("/old", "talker_old")
        listener = start_ros1_node(
            "listener.py", ["/heard", "std_msgs/String", "__name:=py_listener"], env
        )
        procs.append(listener)
        listener.expect("ready", 20)
        rec_all = Proc(["rosbag", "record", "-a", "-O", str(tmp_path / "all.bag"),
                        "__name:=rec_all"], env=env)  # fmt: skip
        rec_named = Proc(["rosbag", "record", "/named", "-O", str(tmp_path / "named.bag"),
                          "__name:=rec_named"], env=env)  # fmt: skip
        procs += [rec_all, rec_named]
        wait_for(
            lambda: (
                "/rec_all" in subs("/old")
                and subs("/named") == ["/rec_named"]
                and any(n.startswith("/py_listener") for n in subs("/heard"))
            ),
            30,
            "the ROS 1 nodes registered",
        )

        kill_master(master, uri)
        master = start_roscore(port, env)
        for topic, name in (("/new", "talker_new"), ("/heard", "talker_heard"),
                            ("/named", "talker_named")):  # fmt: skip
            talker(topic, name)
        later = talker("/old", "talker_old2")
        # rosbag record -a finds /new on its next poll: new registrations reach the new master
        wait_for(lambda: subs("/new") == ["/rec_all"], 20, "rosbag record -a on /new")
        later.expect(r"said hello 40", 20)  # 2 s of messages from the later publishers

        # what was registered before the restart was never registered again
        assert publishers(uri, "/old") == ["/talker_old2"]  # not the rospy talker_old
        assert subs("/old") == []  # not rosbag record -a (roscpp)
        # nor rosbag record /named (roscpp), nor the rospy listener; -a subscribed to both anew
        assert subs("/named") == ["/rec_all"]
        assert subs("/heard") == ["/rec_all"]
        with pytest.raises(AssertionError):  # nothing it printed, nor prints now, says "got"
            listener.expect(r"^got ", 1.0)
        for rec in (rec_all, rec_named):
            rec.signal(signal.SIGINT)
            rec.popen.wait(20)
    finally:
        for proc in procs:
            proc.stop()
        master.stop()

    def recorded(bag: str) -> dict[str, set[str]]:
        """Each topic's publishers (callerids) that the bag holds messages from."""
        by_topic: dict[str, set[str]] = {}
        with open_bag(tmp_path / bag) as reader:
            for conn, _, _ in reader.messages():
                by_topic.setdefault(conn.topic, set()).add(conn.callerid)
        return by_topic

    everything = recorded("all.bag")
    assert everything["/new"] == {"/talker_new"}  # a topic new to it: its publisher recorded
    assert everything["/heard"] == {"/talker_heard"}
    assert everything["/old"] == {"/talker_old"}  # a topic it had: the later talker missed
    assert "/named" in everything and everything["/named"] == {"/talker_named"}
    assert recorded("named.bag") == {}  # named topics: no later publisher heard
