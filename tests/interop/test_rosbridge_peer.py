"""The rosbridge v2 protocol with clients nobody here wrote, against each server in
``SERVERS``: roslib 2.1.0 in node and roslibpy 2.1.0 (rostools bridge on both masters), and
the parity recorder's answers compared with those of the real rosbridge_server 0.11.17
(``tests/peers/rosbridge/golden.json``).

Each test starts a loopback master, ``rosbridge_graph.py`` (a rospy node with a talker, a
service, an echo and a parameter) and the server, on free ports, and stops them by PID.
"""

from __future__ import annotations

import contextlib
import json
import subprocess
import sys
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from tests.support.foxglove import start_bridge
from tests.support.load import factor, scaled
from tests.support.procs import free_port, ros_env, start_rostools_core
from tests.support.rosbridge import (
    PEER,
    rosbridge_graph,
    rosbridge_missing,
    start_rosbridge,
    start_rosmaster,
)
from tests.support.rosbridge_parity import GOLDEN, differences, record, without_own
from tests.support.web import WEB, node_missing

pytestmark = [pytest.mark.interop]

#: The servers every test here runs against: the same checks and the same golden answers
#: hold for both.
SERVERS = ["rosbridge_server", "rostools"]


@dataclass
class Server:
    """A rosbridge v2 server on a graph of ``rosbridge_graph.py``."""

    kind: str
    url: str
    port: int


#: The masters the real clients' checks run on, for rostools bridge: the real one, and ours.
MASTERS = ["rosmaster", "rostools core"]


@contextlib.contextmanager
def serving(kind: str, master_kind: str, home: Path) -> Iterator[Server]:
    """The server ``kind`` on a fresh master of ``master_kind`` with the test graph."""
    if reason := rosbridge_missing():
        pytest.skip(reason)
    if master_kind == "rosmaster":
        master, uri = start_rosmaster(home)
    else:
        port = free_port()
        uri = f"http://127.0.0.1:{port}"
        master = start_rostools_core(port, {**ros_env(uri, home), "HOME": str(home / "home")})
    try:
        with rosbridge_graph(uri, home):
            if kind == "rostools":
                env = {**ros_env(uri, home), "HOME": str(home / "home")}
                proc, url = start_bridge(env, "--protocol", "rosbridge")
                try:
                    yield Server(kind, url, int(url.rsplit(":", 1)[1]))
                finally:
                    proc.stop()
                return
            bridge = start_rosbridge(uri, home)
            try:
                yield Server(kind, bridge.url, bridge.port)
            finally:
                bridge.stop()
    finally:
        master.stop()


@pytest.fixture(params=SERVERS)
def server(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[Server]:
    """The server ``request.param`` on a fresh ``rosmaster --core`` (the golden answers')."""
    with serving(request.param, "rosmaster", tmp_path) as found:
        yield found


@pytest.fixture(
    params=[("rosbridge_server", "rosmaster")] + [("rostools", m) for m in MASTERS],
    ids=lambda p: f"{p[0]} on {p[1]}",
)
def any_server(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[Server]:
    """Each server, rostools bridge on each master."""
    with serving(*request.param, tmp_path) as found:
        yield found


def checks(argv: list[str], cwd: Path, timeout: float) -> list[dict[str, Any]]:
    """Run a checks script (one JSON line per check, then a summary); its checks' lines."""
    done = subprocess.run(
        argv, cwd=cwd, capture_output=True, text=True, timeout=scaled(timeout), check=False
    )
    lines = [json.loads(line) for line in done.stdout.splitlines() if line.startswith("{")]
    assert lines and lines[-1].get("summary"), f"{argv[1]} ended early: {done.stderr[-3000:]}"
    failed = [line for line in lines[:-1] if not line["ok"]]
    assert not failed, f"{argv[1]}: failed checks: {failed}\n{done.stderr[-2000:]}"
    assert done.returncode == 0
    return lines[:-1]


def test_roslib_in_node(any_server: Server) -> None:
    if reason := node_missing():
        pytest.skip(reason)
    if not (WEB / "node_modules" / "roslib").is_dir():
        pytest.skip("roslib is not installed in tests/peers/web: run npm ci there")
    argv = ["node", str(WEB / "roslib-client.mjs"), any_server.url, f"{factor():.2f}"]
    done = checks(argv, WEB, 180)
    assert [c["check"] for c in done] == [
        "connect", "getTopics", "getServices", "getNodes", "getTopicType", "getServiceType",
        "getMessageDetails", "Param get and set", "subscribe (JSON), 10 messages",
        "subscribe (compression cbor)", "publish, rospy echoes it", "callService",
        "callService, a missing service fails", "advertise a service, rospy calls it",
    ]  # fmt: skip


def test_roslibpy(any_server: Server) -> None:
    pytest.importorskip("roslibpy", reason="roslibpy is in the test extra: pip install -e .[test]")
    script = PEER / "roslibpy_checks.py"
    argv = [sys.executable, str(script), "127.0.0.1", str(any_server.port), f"{factor():.2f}"]
    done = checks(argv, PEER, 180)
    assert len(done) == 11


#: The steps where rostools says what it refused in a ``status`` (rosbridge_server 0.11.17
#: only logs it), and the id each status carries (that of the op refused).
REFUSED = {
    "malformed JSON": None, "unknown op": "unknown-op", "no op": "no-op",
    "publish, no such field": "pub-bad-field", "publish, wrong field type": "pub-bad-type",
    "subscribe, unknown type": "sub-bad-type", "call_service missing": "call-missing",
    "call_service /set_flag, bad args": "call-bad-args",
}  # fmt: skip


def test_parity_with_rosbridge_server(server: Server) -> None:
    golden = without_own(json.loads(GOLDEN.read_text()), "rosbridge_server")
    answers = record(server.url)
    assert list(answers) == list(golden)  # the same steps, in the same order
    # statuses aside: rosbridge_server sends none, rostools one for each op it refuses
    statuses = {
        step: [m for m in said if m.get("op") == "status"] for step, said in answers.items()
    }
    ours = without_own(
        {s: [m for m in said if m.get("op") != "status"] for s, said in answers.items()},
        server.kind,
    )
    found = differences(golden, ours)
    assert not found, "answers differ from rosbridge_server's:\n" + "\n".join(found)
    if server.kind == "rostools":
        said = {
            step: [(m["level"], m.get("id")) for m in got] for step, got in statuses.items() if got
        }
        assert said == {step: [("error", ident)] for step, ident in REFUSED.items()}
