"""The one graph every online case runs against, on a real roscore or on rostools core.

A rospy talker (/chatter, logging to /rosout), the AddTwoInts server (/add_two_ints,
/trigger, /slow), ``graph_peer.py`` (/point with a header, /joints, the latched /latched,
a subscriber of /chatter, /set_bool and /empty) and the parameters below. Every process is
started in its own session on a free loopback port and stopped by its PID
(tests/support/procs.py).
"""

from __future__ import annotations

import contextlib
import shutil
import signal
import subprocess
import sys
import time
import xmlrpc.client
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tests.support.procs import (
    Proc,
    free_port,
    ros_env,
    start_ros1_node,
    start_roscore,
    start_rostools_core,
    wait_for,
)

PEER = Path(__file__).with_name("graph_peer.py")
SYSTEM_PYTHON = "/usr/bin/python3"

#: The parameters every master starts with (under /p, plus one at the top), restored
#: before each case that changes them.
PARAMS: dict[str, object] = {
    "int": 42,
    "neg": -7,
    "float": 3.5,
    "small": 1.0e-5,
    "bool_t": True,
    "bool_f": False,
    "text": "hello world",
    "multiline": "line one\nline two\n",
    "empty": "",
    "unicode": "h\u00e9llo",
    "numeric_str": "123",
    "list": [1, 2, 3],
    "mixed": [1, "two", 3.0, True],
    "nested": {"a": {"b": {"c": 1}}, "list_in": [1, 2], "s": "x"},
    "empty_map": {},
}
TOP = ("/top", "top level")

#: The topics the graph publishes, which every online case may wait on.
TOPICS = ("/chatter", "/point", "/joints", "/latched", "/rosout")
SERVICES = ("/add_two_ints", "/trigger", "/slow", "/set_bool", "/empty")


@dataclass
class Graph:
    """A running graph: which master, its URI, and the environment both tools run in."""

    kind: str
    uri: str
    env: dict[str, str]
    procs: list[Proc]

    def call(self, method: str, *args: object) -> Any:
        """The value of a Master or Parameter API call (``[code, text, value]``)."""
        return master_call(self.uri, method, *args)

    def reset_params(self) -> None:
        """Put /p, /top and /scratch back as the graph started."""
        for name in ("/p", "/scratch", TOP[0]):
            if self.call("hasParam", name):
                self.call("deleteParam", name)
        self.call("setParam", "/p", PARAMS)
        self.call("setParam", TOP[0], TOP[1])


def master_call(uri: str, method: str, *args: object) -> Any:
    """The value of a call to the master at ``uri``, as the caller /parity."""
    with xmlrpc.client.ServerProxy(uri) as m:
        code, text, value = getattr(m, method)("/parity", *args)
    if code != 1:
        raise RuntimeError(f"{method}{args}: {text}")
    return value


def _topics(uri: str) -> set[str]:
    return {t for t, _ in master_call(uri, "getPublishedTopics", "")}


def _services(uri: str) -> set[str]:
    return {s for s, _ in master_call(uri, "getSystemState")[2]}


@contextlib.contextmanager
def graph(kind: str, home: Path) -> Iterator[Graph]:
    """The graph on ``kind`` ("roscore" or "rostools"), torn down on exit."""
    port = free_port()
    uri = f"http://127.0.0.1:{port}/"
    home.mkdir(parents=True, exist_ok=True)
    env = ros_env(uri, home)
    procs: list[Proc] = []
    try:
        if kind == "roscore":
            procs.append(start_roscore(port, env))
        else:
            procs.append(start_rostools_core(port, env))
        g = Graph(kind, uri, env, procs)
        g.reset_params()
        procs.append(start_ros1_node("talker.py", ["/chatter", "10"], env))
        procs.append(start_ros1_node("add_two_ints_server.py", ["0.2"], env))
        peer = Proc([SYSTEM_PYTHON, str(PEER)], env=env)
        peer.stop_timeout = 1.0
        procs.append(peer)
        wait_for(lambda: set(TOPICS) <= _topics(uri), 30, f"the graph's topics on {kind}")
        wait_for(lambda: set(SERVICES) <= _services(uri), 30, f"the graph's services on {kind}")
        time.sleep(1.0)  # the first messages flow, /rosout has its subscribers
        yield g
    finally:
        for proc in reversed(procs):
            proc.stop()


def record_bags(g: Graph, folder: Path, seconds: float = 3.0) -> list[Path]:
    """``graph.bag`` (plain) and ``graph_lz4.bag`` written by real rosbag from ``g``."""
    folder.mkdir(parents=True, exist_ok=True)
    topics = ["/chatter", "/point", "/joints", "/latched"]
    argv = [
        ["rosbag", "record", "-q", "-O", "graph.bag", *topics],
        ["rosbag", "record", "-q", "--lz4", "-O", "graph_lz4.bag", *topics],
    ]
    recorders = [Proc(a, env=g.env, cwd=folder, stdout=subprocess.DEVNULL) for a in argv]
    out = [folder / "graph.bag", folder / "graph_lz4.bag"]
    try:
        time.sleep(seconds + 1.0)  # rosbag takes about a second to subscribe
        for r in recorders:
            r.signal(signal.SIGINT)
        # rosbag's Python front end exits at once; its C++ recorder closes the file after.
        wait_for(lambda: all(p.exists() for p in out), 15, "rosbag record to close its bags")
    finally:
        for r in recorders:
            r.stop(10)
    for path in out:
        if not path.exists():
            raise RuntimeError(f"rosbag record wrote no {path.name}")
    return out


def rostools_argv() -> list[str]:
    """The rostools under test: the console script beside this interpreter."""
    exe = Path(sys.executable).with_name("rostools")
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "rostools"]


def have_ros1() -> str | None:
    """Why the real ROS 1 cannot be used here, or None."""
    for tool in ("roscore", "rostopic", "rosservice", "rosparam", "rosnode", "rosmsg", "rosbag"):
        if shutil.which(tool) is None:
            return f"{tool} is not installed (scripts/install-ros1-peers.sh)"
    return None
