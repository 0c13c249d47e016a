"""Actions between rostools and real actionlib (rospy), on one master for the module.

Our ``action send-goal`` against a real ``SimpleActionServer``: succeed, abort, preempt by
timeout and by Ctrl-C, and a server that dies mid-goal. A real ``SimpleActionClient``
against a server written with ``rostools.action``. The peers are
``tests/support/ros1_nodes/action_server.py``/``action_client.py`` and
``tests/support/rt_nodes/rt_actions.py``; a goal's number picks its outcome.
"""

from __future__ import annotations

import json
import signal
import sys
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.support.env import needs_ros1, run_cli
from tests.support.load import scaled
from tests.support.procs import (
    Proc,
    core_and_env,
    ros_env,
    start_cli,
    start_ros1_node,
    wait_for,
)

pytestmark = [pytest.mark.interop, needs_ros1]

ROOT = Path(__file__).resolve().parent.parent.parent
RT_ACTIONS = ROOT / "tests" / "support" / "rt_nodes" / "rt_actions.py"
ACTIONLIB = Path("/usr/lib/python3/dist-packages/actionlib/simple_action_server.py")


class Graph:
    """The module's master, with environments for rostools and for rospy."""

    def __init__(self, cli_env: dict[str, str], ros: dict[str, str]) -> None:
        self.cli_env = cli_env
        self.ros_env = ros

    def listed(self, name: str) -> None:
        wait_for(lambda: name in run_cli("action", "list", env=self.cli_env).stdout, 20, name)


@pytest.fixture(scope="module")
def graph(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Graph]:
    if not ACTIONLIB.is_file():
        pytest.skip("python3-actionlib is not installed (scripts/install-ros1-peers.sh)")
    tmp = tmp_path_factory.mktemp("actions")
    core, env = core_and_env(tmp)
    try:
        yield Graph(env, ros_env(env["ROS_MASTER_URI"], tmp / "ros_home"))
    finally:
        core.stop()


@pytest.fixture(scope="module")
def rospy_server(graph: Graph) -> Iterator[str]:
    server = start_ros1_node("action_server.py", ["/fib"], graph.ros_env)
    try:
        server.expect("ready", 30)
        graph.listed("/fib")
        yield "/fib"
    finally:
        server.stop()


def events(stdout: str) -> list[dict[str, Any]]:
    return [json.loads(line) for line in stdout.splitlines()]


def send_goal(graph: Graph, *args: str) -> tuple[int, list[dict[str, Any]], str]:
    done = run_cli("action", "send-goal", "-F", "json", *args, env=graph.cli_env)
    assert "Traceback" not in done.stderr
    return done.returncode, events(done.stdout), done.stderr


def test_send_goal_to_a_rospy_server(graph: Graph, rospy_server: str) -> None:
    code, got, err = send_goal(graph, rospy_server, "{goal: 3}", "--feedback")
    assert code == 0, err
    assert [e["feedback"]["feedback"] for e in got if e["event"] == "feedback"] == [1, 2, 3]
    assert (got[-1]["status"], got[-1]["text"], got[-1]["result"]) == (
        "SUCCEEDED", "done", {"result": 30},
    )  # fmt: skip
    code, got, err = send_goal(graph, rospy_server, "--", "-2")
    assert code == 7 and err.endswith("was aborted (negative goal -2)\n"), err
    # --timeout cancels the goal on the server: it preempts it, and says so before we exit
    code, got, err = send_goal(graph, rospy_server, "1000", "--timeout", "0.8")
    assert code == 5 and "canceled it" in err, err
    assert {"event": "cancel", "goal_id": got[0]["goal_id"], "reason": "timeout"} in got
    assert got[-1]["event"] == "result" and got[-1]["status"] == "PREEMPTED"
    assert got[-1]["text"].startswith("preempted at ")
    # Ctrl-C too
    sender = start_cli("action", "send-goal", rospy_server, "1000", "-F", "json", env=graph.cli_env)
    try:
        sender.expect('"ACTIVE"', 20)
        sender.signal(signal.SIGINT)
        assert json.loads(sender.expect('"event": ?"result"', 10))["status"] == "PREEMPTED"
        assert sender.popen.wait(10) == 130
    finally:
        sender.stop()
    table = run_cli("action", "status", rospy_server, "--once", "-F", "json", env=graph.cli_env)
    states = [g["status"] for g in json.loads(table.stdout)["goals"]]
    # actionlib keeps a finished goal's status for 5 s (status_list_timeout): on a loaded
    # machine the first goals are gone by now, the last two preempted ones are not
    assert states.count("PREEMPTED") == 2, states
    assert set(states) <= {"SUCCEEDED", "ABORTED", "PREEMPTED"}, states


def test_a_server_that_dies_mid_goal(graph: Graph) -> None:
    server = start_ros1_node("action_server.py", ["/doomed"], graph.ros_env)
    try:
        server.expect("ready", 30)
        graph.listed("/doomed")
        started = time.monotonic()
        code, got, err = send_goal(graph, "/doomed", "666", "--feedback")
        assert time.monotonic() - started < scaled(10)
        assert code == 4, err
        assert [e["event"] for e in got][-2:] == ["feedback", "lost"]
        assert err.count("\n") == 1 and "the action server of /doomed went away" in err, err
    finally:
        server.stop()


def test_a_rospy_client_of_a_rostools_server(graph: Graph) -> None:
    server = Proc([sys.executable, str(RT_ACTIONS), "/ours", "actionlib/TestAction"],
                  env=graph.cli_env)  # fmt: skip
    try:
        server.expect("ready", 20)
        client = start_ros1_node("action_client.py", ["/ours", "3", "-2", "13", "1000"],
                                 graph.ros_env)  # fmt: skip
        try:
            lines = [client.expect(r"^result ", 30).split(" ", 5) for _ in range(4)]
        finally:
            client.stop()
        assert [line[:5] for line in lines[:3]] == [
            ["result", "3", "SUCCEEDED", "30", "3"],
            ["result", "-2", "ABORTED", "0", "0"],
            ["result", "13", "REJECTED", "0", "0"],
        ]
        assert [line[5].strip() for line in lines[:3]] == ["", "negative goal -2", "unlucky"]
        # canceled after its third feedback; a fourth may have been on its way, and the last
        # feedback may come after the result: they travel on two connections
        _, _, state, result, count, text = lines[3]
        assert (state, text.strip()) == ("PREEMPTED", f"canceled at {result}")
        assert int(result) in (3, 4) and int(count) in (int(result) - 1, int(result))
    finally:
        server.stop()
