"""``rostools node`` beside the real ``rosnode``, on real rospy and roscpp nodes, on both masters.

Both tools look at the same live graph, so their text must agree; only round-trip times are
hidden. ``any_master`` runs each test on ``rostools core`` and on a real ``roscore``; on ours,
both cores run a ``/rosout`` node (roscore's roscpp one, rostools core's own), so both graphs
hold the same nodes.
"""

from __future__ import annotations

import re
import signal
import subprocess
import time
from collections.abc import Iterator

import pytest

from tests.conftest import MasterInfo
from tests.support.env import needs_ros1, run_cli
from tests.support.procs import Proc, start_ros1_node, wait_for

pytestmark = [pytest.mark.interop, needs_ros1]


def rosnode(info: MasterInfo, *args: str) -> subprocess.CompletedProcess[str]:
    """The real rosnode against the master."""
    return subprocess.run(
        ["rosnode", *args],
        env=info.ros_env,
        capture_output=True,
        text=True,
        stdin=subprocess.DEVNULL,
        timeout=60,
        check=False,
    )


def ours(info: MasterInfo, *args: str) -> subprocess.CompletedProcess[str]:
    """``rostools node ARGS`` against the master."""
    return run_cli("node", *args, env=info.cli_env)


def hide_times(text: str) -> str:
    """Round-trip times differ from run to run; rosnode's "node is" line is its own."""
    text = re.sub(r"time=\d+\.\d+ms", "time=T", text)
    text = re.sub(r"ping average: \d+\.\d+ms", "ping average: T", text)
    return "\n".join(line for line in text.splitlines() if not line.startswith("rosnode: node is"))


def agree(info: MasterInfo, *args: str, timeout: float = 8.0) -> str:
    """Run ``rosnode ARGS`` and ``rostools node ARGS`` until their stdout agree; that text.

    Retried, for up to ``timeout`` seconds, because connections settle for a moment after
    nodes start (rosout connecting); each round of the two takes about a second itself.
    """
    deadline = time.monotonic() + timeout
    while True:
        theirs, mine = rosnode(info, *args), ours(info, *args)
        assert theirs.returncode == 0, theirs.stderr
        assert mine.returncode == 0, mine.stderr
        if hide_times(theirs.stdout) == hide_times(mine.stdout):
            return mine.stdout
        if time.monotonic() > deadline:
            break
    assert hide_times(mine.stdout) == hide_times(theirs.stdout), args
    return mine.stdout


@pytest.fixture
def graph(any_master: MasterInfo) -> Iterator[dict[str, Proc]]:
    """A rospy talker and listener exchanging messages; both masters run a /rosout node."""
    env = any_master.ros_env
    procs: dict[str, Proc] = {}
    procs["talker"] = start_ros1_node("talker.py", ["/chatter", "20"], env)
    procs["listener"] = start_ros1_node(
        "listener.py", ["/chatter", "std_msgs/String", "__name:=listener"], env
    )
    try:
        procs["listener"].expect(r"got hello \d+", timeout=30)
        wait_for(
            lambda: ours(any_master, "list").stdout == "/listener\n/rosout\n/talker\n",
            20,
            "the three nodes",
        )
        yield procs
    finally:
        for proc in procs.values():
            proc.stop()


def test_list_info_and_machine_agree_with_rosnode(
    any_master: MasterInfo, graph: dict[str, Proc]
) -> None:
    assert agree(any_master, "list") == "/listener\n/rosout\n/talker\n"
    agree(any_master, "list", "-u")
    agree(any_master, "list", "-a")
    agree(any_master, "list", "/ros")
    agree(any_master, "machine")
    assert agree(any_master, "machine", "127.0.0.1") == "/listener\n/rosout\n/talker\n"
    agree(any_master, "info", "-q", "/talker", "/listener")
    talker = agree(any_master, "info", "/talker")  # rospy, outbound connections
    assert "    * to: /listener\n    * direction: outbound (" in talker
    listener = agree(any_master, "info", "/listener")  # rospy, an inbound connection
    assert re.search(r"    \* to: /talker \(http://127\.0\.0\.1:\d+/\)\n", listener)
    rosout = agree(any_master, "info", "/rosout")  # roscpp, inbound from both
    assert "Pid: " in rosout and rosout.count("* topic: /rosout") == 2


def test_ping_agrees_with_rosnode(any_master: MasterInfo, graph: dict[str, Proc]) -> None:
    out = agree(any_master, "ping", "-c", "2", "/talker")
    assert out.count("xmlrpc reply from") == 2 and "ping average" in out
    agree(any_master, "ping", "-c", "1", "/rosout")
    theirs, mine = rosnode(any_master, "ping", "--all"), ours(any_master, "ping", "--all")
    # rosnode pings in set order; the lines are the same
    assert sorted(hide_times(mine.stdout).splitlines()) == sorted(
        hide_times(theirs.stdout).splitlines()
    )
    assert mine.returncode == 0
    # deliberate difference: an unknown node is an error here, exit 0 in rosnode
    theirs, mine = rosnode(any_master, "ping", "/nope"), ours(any_master, "ping", "/nope")
    assert (theirs.returncode, theirs.stderr) == (0, "cannot ping [/nope]: unknown node\n")
    assert mine.returncode == 3 and "unknown node /nope" in mine.stderr
    theirs, mine = rosnode(any_master, "info", "/nope"), ours(any_master, "info", "/nope")
    assert theirs.returncode == 0 and mine.returncode == 3


def test_kill_stops_rospy_nodes_as_rosnode_does(
    any_master: MasterInfo, graph: dict[str, Proc]
) -> None:
    mine = ours(any_master, "kill", "/talker")
    assert (mine.returncode, mine.stdout, mine.stderr) == (0, "killing /talker\nkilled\n", ""), (
        mine.stderr
    )
    theirs = rosnode(any_master, "kill", "/listener")
    assert (theirs.returncode, theirs.stdout) == (0, "killing /listener\nkilled\n")
    # both rospy processes exit, and unregister on the way out
    assert graph["talker"].popen.wait(20) is not None
    assert graph["listener"].popen.wait(20) is not None
    wait_for(lambda: ours(any_master, "list").stdout == "/rosout\n", 20, "talker and listener gone")
    assert rosnode(any_master, "list").stdout == "/rosout\n"
    mine = ours(any_master, "kill", "/talker")
    theirs = rosnode(any_master, "kill", "/talker")
    assert mine.returncode == 3 and "unknown node /talker" in mine.stderr
    assert theirs.returncode == 1 and "Unknown node(s)" in theirs.stderr


def test_kill_stops_a_roscpp_node(any_master: MasterInfo) -> None:
    # roscore's own rosout would be respawned by its launcher: start another roscpp node
    node = Proc(["/usr/lib/rosout/rosout", "__name:=cpp_node"], env=any_master.ros_env)
    try:
        wait_for(lambda: "/cpp_node" in ours(any_master, "list").stdout.split(), 20, "cpp_node")
        mine = ours(any_master, "kill", "/cpp_node")
        assert (mine.returncode, mine.stdout, mine.stderr) == (0, "killing /cpp_node\nkilled\n", "")
        assert node.popen.wait(20) is not None
        wait_for(lambda: "/cpp_node" not in ours(any_master, "list").stdout.split(), 20, "gone")
    finally:
        node.stop()


def test_cleanup_purges_a_sigkilled_node(any_master: MasterInfo, graph: dict[str, Proc]) -> None:
    listener = graph["listener"]
    listener.signal(signal.SIGKILL)  # no chance to unregister
    listener.popen.wait(10)
    assert "/listener" in rosnode(any_master, "list").stdout.split()
    # the answer through a pipe, as `echo y | rosnode cleanup` takes it
    mine = run_cli("node", "cleanup", env=any_master.cli_env, input="y\n")
    assert mine.returncode == 0, mine.stderr
    assert mine.stdout.startswith("Unable to contact the following nodes:\n * /listener (")
    assert mine.stdout.endswith("Unregistering /listener\ndone\n")
    assert rosnode(any_master, "list").stdout == "/rosout\n/talker\n"
    chatter = subprocess.run(
        ["rostopic", "info", "/chatter"],
        env=any_master.ros_env,
        capture_output=True,
        text=True,
        timeout=60,
        check=False,
    ).stdout
    assert "Subscribers: None" in chatter and "/listener" not in chatter
    # rosnode finds nothing left to clean up either (it would list /listener and ask)
    theirs = subprocess.run(
        ["rosnode", "cleanup"],
        env=any_master.ros_env,
        capture_output=True,
        text=True,
        input="n\n",
        timeout=60,
        check=False,
    )
    assert (theirs.returncode, theirs.stdout) == (0, "")


def test_graph_matches_rostopic(any_master: MasterInfo, graph: dict[str, Proc]) -> None:
    out = ours(any_master, "graph")
    assert out.returncode == 0, out.stderr
    assert out.stdout == (
        "/listener\n"
        "└── subscribes\n"
        "    └── /chatter [std_msgs/String] ← /talker\n"
        "/talker\n"
        "└── publishes\n"
        "    └── /chatter [std_msgs/String] → /listener\n"
    )
    everything = ours(any_master, "graph", "--all").stdout
    assert "    └── /rosout [rosgraph_msgs/Log] ← /listener, /talker\n" in everything


@pytest.mark.roslaunch  # roslaunch respawns rosout
def test_rosout_comes_back_after_a_real_rosnode_kill(any_master: MasterInfo) -> None:
    """roscore respawns its rosout; rostools core does the same (a new node URI each time)."""

    def uri() -> str:  # an empty graph lists as "\n", as rosnode's does
        return ours(any_master, "list", "-u").stdout.strip()

    def settled() -> bool:  # rosout's last registration is a logger service
        listed = run_cli("service", "list", env=any_master.cli_env).stdout
        return "/rosout/set_logger_level" in listed

    wait_for(settled, 20, "rosout to finish starting")
    before = uri()
    killed = rosnode(any_master, "kill", "/rosout")
    assert killed.returncode == 0 and "killed" in killed.stdout, killed.stderr
    wait_for(lambda: uri() not in ("", before), 20, "a new /rosout")
    assert ours(any_master, "list").stdout == "/rosout\n"
