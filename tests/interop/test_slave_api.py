"""Our slave API answers malformed calls exactly as rospy's does, asked side by side."""

from __future__ import annotations

import xmlrpc.client
from pathlib import Path
from typing import Any

import pytest

from tests.support.env import needs_ros1
from tests.support.procs import ros_env, start_cli, start_ros1_node, wait_for

pytestmark = [pytest.mark.interop, needs_ros1]

#: (method, params): every one is refused, or answered the same by any node
CALLS: list[tuple[str, tuple[Any, ...]]] = [
    ("publisherUpdate", ("/c", "/bad_topic", "bad")),  # a string where the URI list belongs
    ("publisherUpdate", ("/c", "/t", [1])),
    ("publisherUpdate", ("/c", "/t", ["no-url"])),
    ("publisherUpdate", ("/c", "", [])),
    ("publisherUpdate", ("/c", "a b", [])),
    ("publisherUpdate", ("/c", "/", [])),
    ("publisherUpdate", ("/c", {"a": 1}, [])),
    ("publisherUpdate", (5, "/t", [])),
    ("publisherUpdate", ("/c",)),
    ("publisherUpdate", ()),
    ("requestTopic", ("/c", "/t", [])),
    ("requestTopic", ("/c", "/not_ours", [["TCPROS"]])),
    ("requestTopic", ("/c", 7, [["TCPROS"]])),
    ("requestTopic", ("/c", "x:y", [["TCPROS"]])),
    ("paramUpdate", ("/c", "relative", 1)),
    ("paramUpdate", ("/c", "/unsubscribed", 1)),
    ("paramUpdate", ("/c", ["/k"], 1)),
    ("shutdown", ("/c",)),
    ("getPid", ("/c", "extra")),
    ("getMasterUri", (1,)),
    ("getBusStats", ()),
    ("getSubscriptions", ("/c", 2)),
    ("getPublications", (None,)),
    ("noSuchMethod", ("/c",)),  # a fault, which a planted bug turned into a triple
]


def _answer(uri: str, method: str, params: tuple[Any, ...]) -> Any:
    """The answer, or ``("fault", code)`` as the standard library's client reads a fault."""
    try:
        return getattr(xmlrpc.client.ServerProxy(uri, allow_none=True), method)(*params)
    except xmlrpc.client.Fault as fault:
        return ("fault", fault.faultCode)


def test_malformed_slave_calls_get_rospys_answers(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    # the defect: publisherUpdate with a string for the URI list got a success from us
    talker = start_ros1_node("talker.py", ["/t", "5"], ros_env(rostools_master, tmp_path))
    ours = start_cli(
        "topic", "pub", "-r", "5", "/t", "std_msgs/String", "data: x", "__name:=ours", env=cli_env
    )
    master = xmlrpc.client.ServerProxy(rostools_master, allow_none=True)
    try:
        wait_for(lambda: all(master.lookupNode("/c", n)[0] == 1 for n in ("/talker", "/ours")))
        uris = [master.lookupNode("/c", n)[2] for n in ("/talker", "/ours")]
        for method, params in CALLS:
            theirs, mine = (_answer(u, method, params) for u in uris)
            assert mine == theirs, (method, params)
    finally:
        ours.stop()
        talker.stop()
