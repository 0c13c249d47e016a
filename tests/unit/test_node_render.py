"""How ``rostools node`` renders: rosnode's text, the graph tree and Graphviz."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

from rostools.cli.node.graph import graph_dot, graph_text
from rostools.cli.node.kill import unreachable_text
from rostools.cli.node.ping import reply_text
from rostools.cli.node.query import info_text
from rostools.cli.node.shared import failure_class
from rostools.errors import NotFoundError, TimeoutExpired, UnreachableError
from rostools.rosgraph.nodeapi import BusConnection, NodeInfo, Probe
from rostools.rosgraph.state import SystemState, build_graph

# `rosnode info /listener` on roscore 1.15.15 with tests/support's talker and listener
# (captured, byte for byte).
ROSNODE_INFO_LISTENER = """\
--------------------------------------------------------------------------------
Node [/listener]
Publications: 
 * /rosout [rosgraph_msgs/Log]

Subscriptions: 
 * /chatter [std_msgs/String]

Services: 
 * /listener/get_loggers
 * /listener/set_logger_level


contacting node http://127.0.0.1:44973/ ...
Pid: 21385
Connections:
 * topic: /rosout
    * to: /rosout
    * direction: outbound (37059 - 127.0.0.1:55652) [8]
    * transport: TCPROS
 * topic: /chatter
    * to: /talker (http://127.0.0.1:45843/)
    * direction: inbound
    * transport: TCPROS

"""  # noqa: W291 - rosnode's trailing spaces

# the getBusInfo answer the listener gave at the same time
BUS_INFO = [
    [2, "/rosout", "o", "TCPROS", "/rosout", True,
     "TCPROS connection on port 37059 to [127.0.0.1:55652 on socket 8]"],
    [1, "http://127.0.0.1:45843/", "i", "TCPROS", "/chatter", True,
     "TCPROS connection on port 55906 to [127.0.0.1:37153 on socket None]"],
    [3, "/gone", "o", "TCPROS", "/chatter", False, ""],
]  # fmt: skip


def listener_info(contacted: bool) -> NodeInfo:
    info = NodeInfo(
        "/listener",
        "http://127.0.0.1:44973/",
        [("/rosout", "rosgraph_msgs/Log")],
        [("/chatter", "std_msgs/String")],
        ["/listener/get_loggers", "/listener/set_logger_level"],
    )
    if contacted:
        info.pid = 21385
        peers = [None, "/talker", None]
        info.connections = [
            (BusConnection.from_bus_info(e), p) for e, p in zip(BUS_INFO, peers, strict=True)
        ]
    return info


def test_info_text_is_rosnodes() -> None:
    assert info_text(listener_info(True)) == ROSNODE_INFO_LISTENER


def test_quiet_info_text_stops_after_the_master_part() -> None:
    text = info_text(listener_info(False))
    assert text == ROSNODE_INFO_LISTENER.split("\n\ncontacting")[0] + "\n"
    assert text.endswith("set_logger_level\n\n")


def test_info_text_of_a_node_without_registrations_or_connections() -> None:
    info = NodeInfo("/n", "http://h:1/", [], [], [], pid=7, connections=[])
    assert info_text(info) == (
        "-" * 80 + "\nNode [/n]\nPublications: None\n\nSubscriptions: None\n\nServices: None\n"
        "\n\ncontacting node http://h:1/ ...\nPid: 7\n\n"
    )


def test_info_data_names_the_peer_on_both_ends() -> None:
    data = listener_info(True).to_data()
    out, inbound, closed = data["connections"]
    assert (out["peer_node"], out["peer_uri"], out["socket"]) == ("/rosout", None, 8)
    assert (inbound["peer_node"], inbound["peer_uri"]) == ("/talker", "http://127.0.0.1:45843/")
    assert closed["connected"] is False
    assert "pid" not in listener_info(False).to_data()


def test_reply_text_is_rosnodes() -> None:
    assert reply_text("http://127.0.0.1:45843/", 3.758669) == (
        "xmlrpc reply from http://127.0.0.1:45843/\ttime=3.758669ms"
    )


def test_unreachable_list() -> None:
    dead = [Probe("/a", "http://h:1/", error=UnreachableError("refused"))]
    assert unreachable_text(dead) == "Unable to contact the following nodes:\n * /a (refused)\n"


def test_several_failures_keep_their_exit_code_when_all_alike() -> None:
    assert failure_class([TimeoutExpired("a"), TimeoutExpired("b")]) is TimeoutExpired
    assert failure_class([NotFoundError("a")]) is NotFoundError
    assert failure_class([TimeoutExpired("a"), UnreachableError("b")]) is UnreachableError


STATE = SystemState.from_master(
    [
        [["/chatter", ["/talker"]], ["/odom", ["/base"]], ["/rosout", ["/talker", "/base"]]],
        [["/chatter", ["/listener", "/logger"]], ["/cmd", ["/base"]]],
        [["/base/reset", ["/base"]], ["/lonely/srv", ["/lonely"]]],
    ]
)
TYPES = {"/chatter": "std_msgs/String", "/odom": "nav_msgs/Odometry", "/cmd": "geometry_msgs/Twist"}


def test_graph_tree() -> None:
    assert graph_text(build_graph(STATE, TYPES)) == (
        "/base\n"
        "├── publishes\n"
        "│   └── /odom [nav_msgs/Odometry] → (no subscribers)\n"
        "└── subscribes\n"
        "    └── /cmd [geometry_msgs/Twist] ← (no publishers)\n"
        "/listener\n"
        "└── subscribes\n"
        "    └── /chatter [std_msgs/String] ← /talker\n"
        "/logger\n"
        "└── subscribes\n"
        "    └── /chatter [std_msgs/String] ← /talker\n"
        "/lonely\n"
        "└── (no topics)\n"
        "/talker\n"
        "└── publishes\n"
        "    └── /chatter [std_msgs/String] → /listener, /logger"
    )


def test_graph_dot() -> None:
    dot = graph_dot(build_graph(STATE, TYPES))
    lines = dot.splitlines()
    assert lines[:2] == ["digraph rosgraph {", "  rankdir=LR;"] and lines[-1] == "}"
    assert '  "n:/talker" [label="/talker", shape=ellipse];' in lines
    assert '  "t:/chatter" [label="/chatter\\nstd_msgs/String", shape=box];' in lines
    assert '  "n:/talker" -> "t:/chatter";' in lines
    assert '  "t:/chatter" -> "n:/logger";' in lines
    assert sum("->" in line for line in lines) == 5  # talker, 2 subscribers, odom, cmd


# A newline, a backslash before an "n", a quote, the 8-bit CSI and U+2028, from peers.
HOSTILE = SystemState.from_master(
    [
        [["/a\n", ["/n\u2028"]], ["/a\\n", ['/q"\x9b31m']]],
        [["/a\n", ['/q"\x9b31m']]],
        [],
    ]
)
HOSTILE_TYPES = {"/a\n": "p/T\n", "/a\\n": "p/T\\"}


def test_graph_tree_escapes_peer_names() -> None:
    # before: "/a" and "" on two lines, and the CSI raw
    assert graph_text(build_graph(HOSTILE, HOSTILE_TYPES)) == (
        "/n\\u2028\n"
        "└── publishes\n"
        '    └── /a\\n [p/T\\n] → /q"\\x9b31m\n'
        '/q"\\x9b31m\n'
        "├── publishes\n"
        "│   └── /a\\n [p/T\\] → (no subscribers)\n"
        "└── subscribes\n"
        "    └── /a\\n [p/T\\n] ← /n\\u2028"
    )


def test_graph_dot_is_one_line_a_statement_and_keeps_names_apart() -> None:
    # before: a newline inside a label or ID split the statement over two lines, and the CSI
    # went to the file raw
    lines = graph_dot(build_graph(HOSTILE, HOSTILE_TYPES)).split("\n")
    assert all(line.isprintable() for line in lines), lines
    assert all(line.endswith((";", "{", "}")) for line in lines), lines
    # "/a\n" and "/a\\n" (a backslash and an n) are two topics: two boxes, two IDs
    boxes = [line for line in lines if "shape=box" in line]
    assert boxes == [
        '  "t:/a\\n" [label="/a\\\\n\\np/T\\\\n", shape=box];',
        '  "t:/a\\\\n" [label="/a\\\\n\\np/T\\\\", shape=box];',
    ]
    assert '  "n:/q\\"\\x9b31m" [label="/q\\"\\\\x9b31m", shape=ellipse];' in lines


def test_graphviz_reads_the_hostile_dot(tmp_path: Path) -> None:
    dot = shutil.which("dot")
    if dot is None:
        pytest.skip("Graphviz's dot is not installed")
    text = graph_dot(build_graph(HOSTILE, HOSTILE_TYPES)) + "\n"
    done = subprocess.run([dot, "-Tplain"], input=text, capture_output=True, text=True, check=False)
    assert done.returncode == 0, done.stderr
    # -Tplain: "node NAME x y w h LABEL ...": two nodes and two topics, each drawn once
    drawn = [line for line in done.stdout.splitlines() if line.startswith("node ")]
    assert len(drawn) == 4, done.stdout
