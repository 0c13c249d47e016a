"""``rostools node`` against ``rostools core``, with fake nodes: small XML-RPC servers here.

A fake node registers on the master like a real one and answers getPid, getBusInfo and
shutdown. A "dead" node is registered with the URI of a port nothing listens on (connection
refused); a "hanging" node's port accepts connections but never answers (timeouts).
"""

from __future__ import annotations

import json
import re
import signal
import socket
import sys
import threading
import time
import xmlrpc.client
from collections.abc import Iterator
from typing import Any

import pytest
import yaml

from tests.support import fakepeer
from tests.support.env import run_cli
from tests.support.load import scaled
from tests.support.procs import free_port, silent_port, start_cli

PID = 4242


class FakeNode(fakepeer.FakeNode):
    """A node's slave API on loopback, registered on the master under ``name``."""

    def __init__(
        self,
        master_uri: str,
        name: str,
        pubs: tuple[tuple[str, str], ...] = (),
        subs: tuple[tuple[str, str], ...] = (),
        services: tuple[str, ...] = (),
    ) -> None:
        self.name = name
        self.bus_info: list[list[Any]] = []
        self.shutdown_called = threading.Event()
        super().__init__(
            {
                "getPid": lambda *_: [1, "", PID],
                "getBusInfo": lambda *_: [1, "bus info", self.bus_info],
                "shutdown": self._shutdown,
                "publisherUpdate": lambda *_: [1, "", 0],
            }
        )
        register(master_uri, name, self.uri, pubs, subs, services)

    def _shutdown(self, *_: Any) -> list[Any]:
        self.shutdown_called.set()
        return [1, "shutdown", 0]


def register(
    master_uri: str,
    name: str,
    uri: str,
    pubs: tuple[tuple[str, str], ...] = (),
    subs: tuple[tuple[str, str], ...] = (),
    services: tuple[str, ...] = (),
) -> None:
    """Register ``name`` at ``uri`` as a real node would."""
    master = xmlrpc.client.ServerProxy(master_uri)
    for topic, type_ in pubs:
        assert master.registerPublisher(name, topic, type_, uri)[0] == 1
    for topic, type_ in subs:
        assert master.registerSubscriber(name, topic, type_, uri)[0] == 1
    for service in services:
        assert master.registerService(name, service, "rosrpc://127.0.0.1:1", uri)[0] == 1


def state(master_uri: str) -> list[Any]:
    return list(xmlrpc.client.ServerProxy(master_uri).getSystemState("/test")[2])


@pytest.fixture
def rostools_master(cli_env: dict[str, str]) -> Iterator[str]:
    """A bare master in-process: no /rosout node, so the graph is only the fake nodes."""
    from rostools.master.server import MasterThread

    with MasterThread() as master:
        cli_env["ROS_MASTER_URI"] = master.uri.rstrip("/")
        yield cli_env["ROS_MASTER_URI"]


@pytest.fixture
def nodes(rostools_master: str) -> Iterator[dict[str, FakeNode]]:
    """/talker publishes /chatter to /ns/listener; both report their connection."""
    talker = FakeNode(
        rostools_master,
        "/talker",
        pubs=(("/chatter", "std_msgs/String"),),
        services=("/talker/get_loggers",),
    )
    listener = FakeNode(rostools_master, "/ns/listener", subs=(("/chatter", "std_msgs/String"),))
    talker.bus_info = [
        [1, "/ns/listener", "o", "TCPROS", "/chatter", True,
         "TCPROS connection on port 4000 to [127.0.0.1:5000 on socket 7]"],
        [2, "/gone", "o", "TCPROS", "/chatter", False, ""],
    ]  # fmt: skip
    listener.bus_info = [
        [1, talker.uri, "i", "TCPROS", "/chatter", True,
         "TCPROS connection on port 5000 to [127.0.0.1:4000 on socket None]"],
    ]  # fmt: skip
    try:
        yield {"talker": talker, "listener": listener}
    finally:
        talker.close()
        listener.close()


@pytest.fixture
def dead_uri(rostools_master: str) -> str:
    """/dead: registered (publisher, subscriber, service) at a port nobody listens on."""
    uri = f"http://127.0.0.1:{free_port()}/"
    register(
        rostools_master,
        "/dead",
        uri,
        pubs=(("/dead_out", "std_msgs/Int32"),),
        subs=(("/chatter", "std_msgs/String"),),
        services=("/dead/get_loggers",),
    )
    return uri


@pytest.fixture
def hanging(rostools_master: str) -> Iterator[str]:
    """/hang: registered at a port that accepts connections and never answers."""
    with silent_port() as port:
        uri = f"http://127.0.0.1:{port}/"
        register(rostools_master, "/hang", uri, pubs=(("/hang_out", "std_msgs/Empty"),))
        yield uri


def cli(env: dict[str, str], *args: str, code: int = 0) -> str:
    """Run ``rostools node ARGS``; check the exit code; its stdout."""
    out = run_cli("node", *args, env=env)
    assert out.returncode == code, (args, out.returncode, out.stdout, out.stderr)
    if code == 0:
        assert out.stderr == "", out.stderr
    return out.stdout


def fails(env: dict[str, str], *args: str, code: int) -> str:
    """Run a failing command; its stderr, which must be one line with no traceback."""
    out = run_cli("node", *args, env=env)
    assert out.returncode == code, (args, out.returncode, out.stdout, out.stderr)
    assert "Traceback" not in out.stderr
    return out.stderr


def test_list(nodes: dict[str, FakeNode], cli_env: dict[str, str]) -> None:
    talker, listener = nodes["talker"].uri, nodes["listener"].uri
    assert cli(cli_env, "list") == "/ns/listener\n/talker\n"
    assert cli(cli_env, "list", "-u") == f"{listener}\n{talker}\n"
    assert cli(cli_env, "list", "--all") == f"{listener} \t/ns/listener\n{talker} \t/talker\n"
    assert cli(cli_env, "list", "/ns") == "/ns/listener\n"
    assert cli(cli_env, "list", "/nowhere") == "\n"
    assert cli(cli_env, "list", "ns") == "/ns/listener\n"  # relative: joins ROS_NAMESPACE
    assert cli({**cli_env, "ROS_NAMESPACE": "/ns"}, "list", "listener") == "/ns/listener\n"
    assert json.loads(cli(cli_env, "list", "-a", "-F", "json")) == [
        {"name": "/ns/listener", "uri": listener},
        {"name": "/talker", "uri": talker},
    ]
    assert json.loads(cli(cli_env, "list", "-u", "--format", "json")) == [listener, talker]


def test_info_prints_registrations_pid_and_connections(
    nodes: dict[str, FakeNode], cli_env: dict[str, str]
) -> None:
    talker, listener = nodes["talker"], nodes["listener"]
    assert cli(cli_env, "info", "/talker") == (
        "-" * 80 + "\n"
        "Node [/talker]\n"
        "Publications: \n"
        " * /chatter [std_msgs/String]\n"
        "\n"
        "Subscriptions: None\n"
        "\n"
        "Services: \n"
        " * /talker/get_loggers\n"
        "\n"
        "\n"
        f"contacting node {talker.uri} ...\n"
        f"Pid: {PID}\n"
        "Connections:\n"
        " * topic: /chatter\n"
        "    * to: /ns/listener\n"
        "    * direction: outbound (4000 - 127.0.0.1:5000) [7]\n"
        "    * transport: TCPROS\n"
        "\n"
    )
    assert [m for m, _ in talker.calls] == ["getPid", "getBusInfo"]
    caller = talker.calls[0][1][0]
    assert re.fullmatch(r"/rosnode_\d+", caller)
    # the listener's inbound peer is a URI: it is named after the node registered there
    text = cli(cli_env, "info", "ns/listener")  # relative names join ROS_NAMESPACE (/)
    assert f"    * to: /talker ({talker.uri})\n    * direction: inbound\n" in text
    quiet = cli(cli_env, "info", "-q", "/talker", "/ns/listener")
    assert quiet.count("-" * 80) == 2 and "contacting" not in quiet and "Pid" not in quiet
    assert len(listener.calls) == 2  # -q did not contact it
    both = json.loads(cli(cli_env, "info", "/talker", "/ns/listener", "-F", "json"))
    assert [b["node"] for b in both] == ["/talker", "/ns/listener"]
    assert both[0]["pid"] == PID and both[0]["publications"] == [
        {"topic": "/chatter", "type": "std_msgs/String"}
    ]
    assert [c["connected"] for c in both[0]["connections"]] == [True, False]
    assert both[1]["connections"][0]["peer_node"] == "/talker"
    one = json.loads(cli(cli_env, "info", "/talker", "-q", "-F", "json"))
    assert one["node"] == "/talker" and "connections" not in one


def test_info_errors(
    nodes: dict[str, FakeNode], dead_uri: str, hanging: str, cli_env: dict[str, str]
) -> None:
    err = fails(cli_env, "info", "/talker", "/nope", code=3)
    assert err == "rostools: unknown node /nope (hint: see 'rostools node list')\n"
    assert nodes["talker"].calls == []  # nothing was printed or asked before the check
    out = run_cli("node", "info", "/dead", env=cli_env)
    assert out.returncode == 4
    assert "Node [/dead]" in out.stdout and f"contacting node {dead_uri} ..." in out.stdout
    assert out.stderr == (
        f"rostools: cannot reach the node /dead at {dead_uri}: Connection refused\n"
    )
    start = time.monotonic()
    err = fails(cli_env, "info", "/hang", "--timeout", "0.5", code=5)
    assert time.monotonic() - start < scaled(10)
    assert err == f"rostools: the node /hang at {hanging} did not answer getPid within 0.5 s\n"
    assert cli(cli_env, "info", "-q", "/dead").startswith("-" * 80)  # -q needs no answer
    data = json.loads(run_cli("node", "info", "/dead", "-F", "json", env=cli_env).stdout)
    assert data["node"] == "/dead" and "Connection refused" in data["error"]


def test_ping(
    nodes: dict[str, FakeNode], dead_uri: str, hanging: str, cli_env: dict[str, str]
) -> None:
    uri = nodes["talker"].uri
    text = cli(cli_env, "ping", "-c", "2", "/talker")
    lines = text.splitlines()
    # rosnode's first line, which we left out
    assert lines[:2] == ["rosnode: node is [/talker]", "pinging /talker with a timeout of 3.0s"]
    assert all(
        re.fullmatch(re.escape(f"xmlrpc reply from {uri}") + r"\ttime=\d+\.\d{6}ms", line)
        for line in lines[2:4]
    ), lines
    assert re.fullmatch(r"ping average: \d+\.\d{6}ms", lines[4]) and len(lines) == 5
    # A YAML stream is documents that each end with ---, as echo's (ping began them with it).
    docs = cli(cli_env, "ping", "/talker", "-c2", "-F", "yaml")
    assert docs.endswith("---\n") and not docs.startswith("---")
    assert [d["seq"] for d in yaml.safe_load_all(docs) if d] == [1, 2]
    stream = cli(cli_env, "ping", "/talker", "-c2", "-F", "json").splitlines()
    replies = [json.loads(line) for line in stream]
    assert [(r["node"], r["uri"], r["seq"], r["pid"]) for r in replies] == [
        ("/talker", uri, 1, PID),
        ("/talker", uri, 2, PID),
    ]
    assert all(r["time_ms"] > 0 for r in replies)
    assert "unknown node /nope" in fails(cli_env, "ping", "/nope", code=3)
    assert "Connection refused" in fails(cli_env, "ping", "/dead", code=4)
    err = fails(cli_env, "ping", "/hang", "-t", "0.3", code=5)
    assert "did not answer getPid within 0.3 s" in err


def test_ping_all_reports_every_node_and_fails_for_the_silent_ones(
    nodes: dict[str, FakeNode], dead_uri: str, cli_env: dict[str, str]
) -> None:
    out = run_cli("node", "ping", "-a", env=cli_env)
    assert out.returncode == 4
    assert out.stdout.startswith(
        "Will ping the following nodes: \n * /dead\n * /ns/listener\n * /talker\n\n"
    )
    assert out.stdout.count("xmlrpc reply from") == 2
    assert out.stderr.splitlines() == [
        f"rostools: cannot reach the node /dead at {dead_uri}: Connection refused",
        "rostools: 1 of 3 nodes did not answer: /dead",
    ]
    replies = run_cli("node", "ping", "--all", "-F", "json", env=cli_env).stdout.splitlines()
    assert sorted(json.loads(r)["node"] for r in replies) == ["/ns/listener", "/talker"]


def test_ping_usage_errors(nodes: dict[str, FakeNode], cli_env: dict[str, str]) -> None:
    assert "-a/--all" in fails(cli_env, "ping", code=2)
    assert "-c may not be used with --all" in fails(cli_env, "ping", "-a", "-c", "2", code=2)
    assert "not both" in fails(cli_env, "ping", "-a", "/talker", code=2)
    fails(cli_env, "ping", "-c", "0", "/talker", code=2)
    fails(cli_env, "ping", "--timeout", "0", "/talker", code=2)


def test_ping_runs_until_ctrl_c_and_prints_the_average(
    nodes: dict[str, FakeNode], cli_env: dict[str, str]
) -> None:
    proc = start_cli("node", "ping", "/talker", env=cli_env)
    try:
        proc.expect(r"^pinging /talker")
        proc.expect(r"^xmlrpc reply from")
        proc.expect(r"^xmlrpc reply from", timeout=5)
        proc.signal(signal.SIGINT)
        assert proc.popen.wait(10) == 0
        proc.expect(r"^ping average: \d+\.\d+ms$", timeout=5)
    finally:
        proc.stop()


def test_ping_follows_a_node_that_moved(rostools_master: str) -> None:
    """A node restarted under the same name has a new URI: ping looks it up again once."""
    from rostools.cli.node.ping import _ping_replies
    from rostools.rosgraph.masterapi import MasterProxy
    from rostools.rosgraph.nodeapi import Graph

    old = f"http://127.0.0.1:{free_port()}/"
    register(rostools_master, "/mover", old, pubs=(("/m", "std_msgs/Empty"),))
    graph = Graph(MasterProxy(rostools_master, "/test"), 2.0)
    assert graph.uri("/mover") == old
    node = FakeNode(rostools_master, "/mover", pubs=(("/m", "std_msgs/Empty"),))
    try:
        [(uri, pid, _)] = list(_ping_replies(graph, "/mover", 1))
        assert (uri, pid) == (node.uri, PID)
    finally:
        node.close()


def test_kill(
    nodes: dict[str, FakeNode], dead_uri: str, cli_env: dict[str, str], rostools_master: str
) -> None:
    talker, listener = nodes["talker"], nodes["listener"]
    err = fails(cli_env, "kill", "/talker", "/nope", "/nope2", code=3)
    assert "unknown nodes /nope, /nope2" in err and not talker.shutdown_called.is_set()
    assert "-a/--all" in fails(cli_env, "kill", code=2)
    assert "not both" in fails(cli_env, "kill", "-a", "/talker", code=2)
    assert cli(cli_env, "kill", "/talker") == "killing /talker\nkilled\n"
    assert talker.shutdown_called.is_set()
    [(caller, reason)] = [args for m, args in talker.calls if m == "shutdown"]
    assert re.fullmatch(r"/rosnode_\d+", caller) and reason == "user request"
    out = run_cli("node", "kill", "--all", env=cli_env)
    assert out.returncode == 4  # /dead cannot be reached
    assert out.stdout == "killing:\n * /dead\n * /ns/listener\n * /talker\nkilled\n"
    assert (
        out.stderr == f"rostools: cannot reach the node /dead at {dead_uri}: Connection refused\n"
    )
    assert listener.shutdown_called.is_set()
    data = json.loads(run_cli("node", "kill", "/talker", "-F", "json", env=cli_env).stdout)
    assert data == {"killed": ["/talker"], "failed": []}


def test_machine(nodes: dict[str, FakeNode], cli_env: dict[str, str]) -> None:
    assert cli(cli_env, "machine") == "127.0.0.1\n"
    assert cli(cli_env, "machine", "127.0.0.1") == "/ns/listener\n/talker\n"
    assert cli(cli_env, "machine", "localhost") == "/ns/listener\n/talker\n"
    assert json.loads(cli(cli_env, "machine", "-F", "json")) == [
        {"host": "127.0.0.1", "nodes": ["/ns/listener", "/talker"]}
    ]
    err = fails(cli_env, "machine", "no-such-host.invalid", code=3)
    assert err == "rostools: cannot resolve machine name no-such-host.invalid to an address\n"


def test_cleanup_purges_only_the_dead(
    nodes: dict[str, FakeNode], dead_uri: str, cli_env: dict[str, str], rostools_master: str
) -> None:
    before = state(rostools_master)
    assert "/dead" in json.dumps(before)
    # the answer comes from stdin, as rosnode reads it: no answer (its end) and "n" are no
    for answer in ("", "n\n", "maybe\n"):
        out = run_cli("node", "cleanup", env=cli_env, input=answer)
        assert out.returncode == 0 and "aborted: nothing was changed" in out.stderr, out.stderr
        assert out.stdout.startswith("Unable to contact the following nodes:\n * /dead (")
        assert state(rostools_master) == before
    dry = json.loads(cli(cli_env, "cleanup", "--dry-run", "-F", "json"))
    assert [u["node"] for u in dry["unreachable"]] == ["/dead"] and dry["purged"] is False
    assert state(rostools_master) == before
    # echo y | rostools node cleanup (it refused a pipe, exit 2, before)
    done = json.loads(run_cli("node", "cleanup", "-F", "json", env=cli_env, input="y\n").stdout)
    assert done["purged"] is True
    assert [(u["kind"], u["name"], u["removed"]) for u in done["unregistered"]] == [
        ("publisher", "/dead_out", True),
        ("subscriber", "/chatter", True),
        ("service", "/dead/get_loggers", True),
    ]
    after = state(rostools_master)
    assert "/dead" not in json.dumps(after)
    assert cli(cli_env, "list") == "/ns/listener\n/talker\n"
    assert ["/chatter", ["/talker"]] in after[0] and ["/chatter", ["/ns/listener"]] in after[1]
    # nothing left to do
    out = run_cli("node", "cleanup", env=cli_env)
    assert (out.returncode, out.stdout) == (0, "")
    assert "nothing to clean up" in out.stderr


def test_cleanup_text(dead_uri: str, cli_env: dict[str, str]) -> None:
    out = cli(cli_env, "cleanup", "-y")
    assert out == (
        "Unable to contact the following nodes:\n"
        f" * /dead (cannot reach the node /dead at {dead_uri}: Connection refused)\n"
        "Unregistering /dead\n"
        "done\n"
    )


def test_graph(nodes: dict[str, FakeNode], cli_env: dict[str, str]) -> None:
    assert cli(cli_env, "graph") == (
        "/ns/listener\n"
        "└── subscribes\n"
        "    └── /chatter [std_msgs/String] ← /talker\n"
        "/talker\n"
        "└── publishes\n"
        "    └── /chatter [std_msgs/String] → /ns/listener\n"
    )
    data = json.loads(cli(cli_env, "graph", "--format", "json"))
    assert data["edges"] == [
        {
            "source": "/talker",
            "target": "/ns/listener",
            "topic": "/chatter",
            "type": "std_msgs/String",
        }
    ]
    assert [t["name"] for t in data["topics"]] == ["/chatter"]
    dot = cli(cli_env, "graph", "-F", "dot")
    assert '"n:/talker" -> "t:/chatter";' in dot and '"t:/chatter" -> "n:/ns/listener";' in dot
    assert json.loads(run_cli("--format", "json", "node", "graph", env=cli_env).stdout) == data
    fails(cli_env, "graph", "-F", "png", code=2)


def test_master_unreachable(cli_env: dict[str, str]) -> None:
    for args in (["list"], ["info", "/a"], ["ping", "/a"], ["kill", "-a"], ["graph"]):
        err = fails(cli_env, *args, code=4)
        assert err.startswith("rostools: cannot reach the master at http://127.0.0.1:9"), err
        assert len(err.splitlines()) == 1


def test_kill_counts_a_node_that_drops_the_connection_as_killed(
    rostools_master: str, cli_env: dict[str, str]
) -> None:
    """A node may exit before its answer to shutdown is out (seen with rospy): that is a kill."""
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(4)
    uri = f"http://127.0.0.1:{server.getsockname()[1]}/"
    register(rostools_master, "/dropper", uri, pubs=(("/d", "std_msgs/Empty"),))
    requests: list[bytes] = []

    def serve_once() -> None:
        conn, _ = server.accept()
        with conn:
            conn.settimeout(10)
            data = b""
            while b"</methodCall>" not in data and (chunk := conn.recv(65536)):
                data += chunk
            requests.append(data)
        server.close()  # gone: a second try would be refused

    thread = threading.Thread(target=serve_once, daemon=True)
    thread.start()
    try:
        assert cli(cli_env, "kill", "/dropper") == "killing /dropper\nkilled\n"
        thread.join(10)
        assert len(requests) == 1 and b"<methodName>shutdown</methodName>" in requests[0]
        # now nothing listens there: a refused connection is a failure (exit 4)
        assert "Connection refused" in fails(cli_env, "kill", "/dropper", code=4)
    finally:
        server.close()


def test_cleanup_asks_on_a_terminal(
    dead_uri: str, cli_env: dict[str, str], rostools_master: str
) -> None:
    import os
    import pty

    for answer, purged in (("n", False), ("y", True)):
        terminal, stdin = pty.openpty()
        proc = start_cli("node", "cleanup", env=cli_env, stdin=stdin)
        os.close(stdin)
        try:
            os.write(terminal, f"{answer}\n".encode())
            assert proc.popen.wait(60) == 0
            out, err = proc.output()
        finally:
            proc.stop()
            os.close(terminal)
        assert out.startswith("Unable to contact the following nodes:\n * /dead (")
        assert "Please type y or n to continue: " in err
        assert ("/dead" not in json.dumps(state(rostools_master))) is purged
        assert out.endswith("Unregistering /dead\ndone\n") is purged
        assert ("aborted: nothing was changed" in err) is not purged


def test_kill_without_names_offers_rosnodes_menu_on_a_terminal(
    nodes: dict[str, FakeNode], cli_env: dict[str, str]
) -> None:
    import pexpect

    argv = ["-m", "rostools", "node", "kill"]
    child = pexpect.spawn(sys.executable, argv, env=cli_env, timeout=20, encoding="utf-8")
    try:
        child.expect("Please enter the number of the node you wish to kill.")
        menu = [line.strip() for line in child.before.splitlines() if line.strip()]
        assert menu == ["1. /ns/listener", "2. /talker"]
        child.sendline("7")  # not on the menu: asked again
        child.expect("ERROR: enter a number from 1 to 2")
        child.sendline("2")
        child.expect("killing /talker")
        child.expect("killed")
        child.expect(pexpect.EOF)
    finally:
        child.close(force=True)
    assert child.exitstatus == 0
    assert nodes["talker"].shutdown_called.is_set()
    assert not nodes["listener"].shutdown_called.is_set()
