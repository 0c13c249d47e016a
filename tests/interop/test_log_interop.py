"""``rostools log`` against rosconsole, rospy and roscpp, on both masters.

A rospy node and a roscpp node log a round at every level each 0.1 s ("LEVEL N"). ``log set``
must change what each publishes to /rosout; ``log list``/``get`` must agree with
``rosconsole list``/``get``; ``log echo`` must print what ``rosconsole echo`` prints.
"""

from __future__ import annotations

import json
import re
import subprocess
import time
from collections.abc import Iterator
from typing import Any

import pytest

from tests.conftest import MasterInfo
from tests.support import cppbuild
from tests.support.env import CORPUS, needs_corpus, needs_ros1, run_cli, run_system_python
from tests.support.load import scaled
from tests.support.procs import Proc, start_cli, start_ros1_node, wait_for

pytestmark = needs_ros1
ANSI = re.compile(r"\033\[[0-9;]*m")
ROUND = re.compile(r"\]: (debug|info|warn|error|fatal) (\d+)$")


class LoggingNodes:
    """Starts nodes of one kind (rospy or roscpp) that log at every level, and stops them.

    Debian's roscpp (log4cxx 0.15) crashes a node once it has answered ``get_loggers``, as
    ``rosconsole list`` shows; so a roscpp node answers one such question, and each question
    gets a node of its own (``start``).
    """

    def __init__(self, kind: str, master: MasterInfo) -> None:
        self.kind, self.master = kind, master
        self.procs: list[Proc] = []
        #: The logger whose level decides what the node's own messages say.
        self.logger = "rosout" if kind == "rospy" else "ros.unknown_package"

    def start(self, suffix: str = "") -> str:
        """A new node, named after its kind and ``suffix``, once it logs and serves."""
        if self.kind == "rospy":
            name = "/log_levels" + suffix
            proc = start_ros1_node("log_levels.py", [name[1:]], self.master.ros_env)
        else:
            name = "/log_levels_cpp" + suffix
            proc = Proc(
                [str(cppbuild.build("log_levels")), "--name", name[1:]], env=self.master.ros_env
            )
        self.procs.append(proc)
        proc.expect("ready", 30)
        wait_for(lambda: _served(self.master, name), 30, f"{name}'s logger services")
        return name

    def stop(self) -> None:
        """Stop every node started."""
        for proc in self.procs:
            proc.stop()


@pytest.fixture(params=["rospy", "roscpp"])
def nodes(request: pytest.FixtureRequest, any_master: MasterInfo) -> Iterator[LoggingNodes]:
    """Logging nodes of each kind on each master."""
    if request.param == "roscpp" and (reason := cppbuild.cpp_missing()) is not None:
        pytest.skip(reason)
    started = LoggingNodes(request.param, any_master)
    try:
        yield started
    finally:
        started.stop()


def _served(master: MasterInfo, name: str) -> bool:
    found = run_cli("service", "list", name, env=master.cli_env).stdout.split()
    return f"{name}/set_logger_level" in found


def _rosconsole(master: MasterInfo, *args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        ["/usr/bin/rosconsole", *args],
        env=master.ros_env,
        capture_output=True,
        text=True,
        timeout=scaled(60),
        check=False,
    )


def _rounds(proc: Proc, level: str, after: int, count: int = 2) -> int:
    """Wait for ``count`` lines of ``level`` numbered past ``after``; the last number."""
    seen = 0
    while True:
        line = proc.expect(rf"\]: {level} \d+$", 30)
        n = int(line.rsplit(" ", 1)[1])
        if n > after:
            seen += 1
            if seen >= count:
                return n


def test_log_set_changes_what_reaches_rosout(any_master: MasterInfo, nodes: LoggingNodes) -> None:
    """debug appears after ``set debug``; info stops after ``set warn`` (both node kinds).

    The messages are told apart by their stamps: /rosout reaches echo later than the node
    logs, so a line read after ``set`` returned may have been logged before it.
    """
    env, node, logger = any_master.cli_env, nodes.start(), nodes.logger
    echo = start_cli("log", "echo", "-l", "debug", "--node", f"^{node}$", "-F", "json", env=env)

    def logged(level: str, after: float, count: int = 2) -> list[dict[str, Any]]:
        """Wait for ``count`` messages at ``level`` stamped after ``after``; all those seen."""
        seen = 0
        while seen < count:
            msg = json.loads(echo.expect(rf'"msg":"{level} \d+"', 30))
            stamp = msg["header"]["stamp"]
            seen += stamp["secs"] + stamp["nsecs"] / 1e9 > after
        return [json.loads(line) for line in echo.seen]

    try:
        logged("info", 0)  # info reaches /rosout at the default level
        done = run_cli("log", "set", node, logger, "debug", env=env)
        assert done.returncode == 0, done.stderr
        logged("debug", 0)
        done = run_cli("log", "set", node, logger, "warn", env=env)
        assert done.returncode == 0, done.stderr
        set_at = time.time()  # the node applied it before it answered
        msgs = logged("warn", set_at, 3)
        after = [
            m
            for m in msgs
            if m["header"]["stamp"]["secs"] + m["header"]["stamp"]["nsecs"] / 1e9 > set_at
        ]
        assert {m["level"] for m in after} == {4, 8, 16}, [m["msg"] for m in after]
    finally:
        echo.stop()


def test_list_and_get_agree_with_rosconsole(any_master: MasterInfo, nodes: LoggingNodes) -> None:
    """The same loggers and levels, each asked of a node of the same kind."""
    env = any_master.cli_env
    ours = run_cli("log", "list", nodes.start("_a"), env=env)
    theirs = _rosconsole(any_master, "list", nodes.start("_b"))
    assert ours.returncode == theirs.returncode == 0, (ours.stderr, theirs.stderr)
    assert ours.stdout.split() == theirs.stdout.split()
    assert nodes.logger in ours.stdout.split()
    ours = run_cli("log", "get", nodes.start("_c"), nodes.logger, env=env)
    theirs = _rosconsole(any_master, "get", nodes.start("_d"), nodes.logger)
    assert (ours.returncode, ours.stdout) == (0, theirs.stdout), ours.stderr


def test_echo_prints_what_rosconsole_echo_prints(
    any_master: MasterInfo, nodes: LoggingNodes
) -> None:
    """The same messages, line for line once rosconsole's escapes are stripped."""
    env, node = any_master.cli_env, nodes.start()
    ours = start_cli("log", "echo", "-l", "info", node, env=env)
    theirs = Proc(
        ["/usr/bin/rosconsole", "echo", "-l", "info", node, "--nocolor"], env=any_master.ros_env
    )
    try:
        # both follow; compare the rounds both printed whole, from one both have seen
        first = max(_rounds(ours, "fatal", -1, 1), _rounds(theirs, "fatal", -1, 1))
        last = min(_rounds(ours, "fatal", first, 3), _rounds(theirs, "fatal", first, 3))
    finally:
        ours.stop()
        theirs.stop()

    def window(proc: Proc) -> list[str]:
        lines = [ANSI.sub("", line).rstrip("\n") for line in proc.seen]
        return [
            line for line in lines if (m := ROUND.search(line)) and first < int(m.group(2)) <= last
        ]

    assert window(ours), ours.seen[-5:]
    assert window(ours) == window(theirs)


def test_log_set_on_a_rostools_node(any_master: MasterInfo) -> None:
    """rostools' own nodes serve the logger services: ``log set`` changes a Python logger."""
    env = any_master.cli_env
    talker = start_cli(
        "topic",
        "pub",
        "/log_chatter",
        "std_msgs/String",
        "data: hi",
        "-r",
        "5",
        "__name:=rt_talker",
        env=env,
    )
    try:
        wait_for(lambda: _served(any_master, "/rt_talker"), 30, "rt_talker's logger services")
        listed = run_cli("log", "list", "/rt_talker", env=env).stdout.split()
        assert "rostools" in listed and "rostools.node.node" in listed
        assert _rosconsole(any_master, "list", "/rt_talker").stdout.split() == listed
        done = run_cli("log", "set", "/rt_talker", "rostools.node.node", "error", env=env)
        assert done.returncode == 0, done.stderr
        got = run_cli("log", "get", "/rt_talker", "rostools.node.node", env=env)
        assert got.stdout == "ERROR\n"
        assert (
            _rosconsole(any_master, "get", "/rt_talker", "rostools.node.node").stdout == got.stdout
        )
    finally:
        talker.stop()


@pytest.mark.parametrize(
    ("args", "code", "words"),
    [
        (["list", "/no_such_node"], 3, "node /no_such_node does not exist"),
        (["get", "/rosout", "no.such.logger"], 2, "does not contain logger no.such.logger"),
        (["set", "/rosout", "ros", "loud"], 2, "invalid level 'loud'"),
        (["echo", "--level", "loud"], 2, "is not one of"),
        (["echo", "--grep", "("], 2, "is not a regular expression"),
    ],
)
def test_bad_input_is_one_line(
    any_master: MasterInfo, args: list[str], code: int, words: str
) -> None:
    got = run_cli("log", *args, env=any_master.cli_env)
    assert got.returncode == code, got.stderr
    assert got.stderr.count("\n") == 1 and words in got.stderr, got.stderr
    assert "Traceback" not in got.stderr


def test_a_node_without_logger_services(any_master: MasterInfo) -> None:
    """A node the master knows that serves no ``get_loggers``: one line, exit 3."""
    from xmlrpc.client import ServerProxy

    # a registration alone makes a node; its URI answers nothing, and it serves no service
    ServerProxy(any_master.uri).registerPublisher(
        "/mute", "/mute_topic", "std_msgs/Empty", "http://127.0.0.1:9/"
    )
    got = run_cli("log", "list", "/mute", env=any_master.cli_env)
    assert got.returncode == 3, got.stderr
    assert got.stderr.count("\n") == 1 and "node /mute does not serve get_loggers" in got.stderr


LOG_BAGS = [
    "ros1/roswire/example.bag",
    "ros1/roswire/hello_world_example.bag",
    "ros1/rosbag.js/example.bag",
    "ros1/rosbag.js/example-lz4.bag",
    "ros1/rosbag.js/example-bz2.bag",
    "ros1/webviz/example.lz4.bag",
    "ros1/rosbag2_bag_v2/test_bag_end_to_end.bag",  # "rosout", relative, with no messages
    "ros1/rosbag2_bag_v2/test_bag_multiple_connections.bag",
]
#: Real rosbag's reading of the log messages echo -b picks: /rosout_agg's, else /rosout's.
ROSBAG_LOGS = """
import json, sys, rosbag
bag = rosbag.Bag(sys.argv[1])
topics = {c.topic for c in bag._get_connections() if c.datatype == "rosgraph_msgs/Log"}
full = {("/" + t if not t.startswith("/") else t): t for t in topics}
topic = full.get("/rosout_agg") or full["/rosout"]
for _, m, _ in bag.read_messages(topics=[topic]):
    h = m.header
    print(json.dumps({"header": {"seq": h.seq, "stamp": {"secs": h.stamp.secs,
        "nsecs": h.stamp.nsecs}, "frame_id": h.frame_id}, "level": m.level, "name": m.name,
        "msg": m.msg, "file": m.file, "function": m.function, "line": m.line,
        "topics": list(m.topics)}))
"""


@needs_corpus
@pytest.mark.parametrize("rel", LOG_BAGS)
def test_echo_bag_equals_what_rosbag_reads(rel: str) -> None:
    """``log echo -b -l debug -F json``: the messages real rosbag decodes, field for field."""
    path = CORPUS / rel
    ours = run_cli("log", "echo", "-b", str(path), "-l", "debug", "--format", "json")
    assert ours.returncode == 0, ours.stderr
    theirs = [json.loads(line) for line in run_system_python(ROSBAG_LOGS, str(path)).splitlines()]
    got = [json.loads(line) for line in ours.stdout.splitlines()]
    assert got or "end_to_end" in rel
    # rosconsole's filter: level at least debug (1); level 0 is no level, and not shown
    assert got == [m for m in theirs if m["level"] >= 1]


@needs_corpus
def test_echo_bag_filters_and_text() -> None:
    """Level, node and text filters on a bag; rosconsole's line for each message."""
    path = CORPUS / "ros1/roswire/example.bag"
    every = run_cli("log", "echo", "-b", str(path), "-l", "debug", "-F", "json").stdout
    msgs = [json.loads(line) for line in every.splitlines()]
    want = [m for m in msgs if m["level"] >= 2 and "mavros" in m["name"] and "EKF" in m["msg"]]
    assert want and len(want) < len(msgs)
    got = run_cli("log", "echo", "-b", str(path), "-l", "info", "--node", "mavros", "--grep", "EKF")
    names = {1: "DEBUG", 2: "INFO ", 4: "WARN ", 8: "ERROR", 16: "FATAL"}
    assert got.stdout.splitlines() == [
        f"[ {names[m['level']]} ] [{m['name']}]: {m['msg']}" for m in want
    ]


@needs_corpus
def test_echo_bag_without_logs_is_one_line() -> None:
    """A bag with no rosgraph_msgs/Log: one line, exit 3."""
    path = CORPUS / "ros1/rosbag.js/example.bag"
    got = run_cli("log", "echo", "-b", str(path), "--topic", "/turtle1/cmd_vel")
    assert got.returncode == 3 and got.stderr.count("\n") == 1, got.stderr
    assert "has no rosgraph_msgs/Log messages on /turtle1/cmd_vel" in got.stderr


#: rosconsole echo's own printing of one message, colour on or off, with -v.
ROSCONSOLE_PRINT = """
import sys
from rospy.rosconsole import RosConsoleEcho
from rosgraph_msgs.msg import Log
msg = Log()
msg.deserialize(bytes.fromhex(sys.argv[1]))
echo = object.__new__(RosConsoleEcho)
echo._nocolor, echo._verbose = sys.argv[2] == "plain", True
echo._level_string_map = {getattr(Log, lv): echo._stringify(lv) for lv in echo.LEVEL_COLOR}
echo._print(msg)
"""


@pytest.mark.parametrize("colour", [False, True])
@pytest.mark.parametrize("level", [1, 2, 4, 8, 16])
def test_each_level_reads_as_rosconsole_prints_it(level: int, colour: bool) -> None:
    """The line and -v's second line, as rosconsole echo's own code prints them.

    rosconsole ends the node's bold with ``\\033[21m`` (double underline on most terminals);
    we end it with ``\\033[22m``, normal intensity: the one escape allowed to differ.
    """
    from rostools.cli.log.echo import LogPrinter, _renderer
    from rostools.cli.output import Format

    renderer = _renderer()
    msg = renderer.codec.message_class("rosgraph_msgs/Log")(
        level=level, name="/n", msg="said 1", file="f.py", function="fn", line=3
    )
    msg.header.stamp.secs, msg.header.stamp.nsecs = 1_700_000_000, 250_000_000
    data = msg.serialize()
    theirs = run_system_python(ROSCONSOLE_PRINT, data.hex(), "colour" if colour else "plain")
    printer = LogPrinter(1, None, None, Format.text, colour, True, None)
    ours = printer.line(renderer.decode(data, 0)[0])
    if not colour:  # rosconsole writes the bold escapes even with --nocolor
        theirs = theirs.replace("\033[1m", "").replace("\033[21m", "")
    assert ours == theirs.replace("\033[21m", "\033[22m")
