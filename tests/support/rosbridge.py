"""The real rosbridge_server (rosbridge_suite 0.11.17, the last ROS 1 release) as a test peer.

``tests/peers/rosbridge/setup.sh`` extracts it from its release tarball (beside the clone, in
``../shared/peers`` like the corpus; ``RBS_TARBALL`` names another copy) into a test's own
folder and generates its message classes. This module then starts ``rosapi_node`` and
``rosbridge_websocket`` on the system python against a test's master, on a free loopback port,
each in a process group of its own, and stops them by PID. A missing piece (ROS 1, the
tarball, an apt package of ``scripts/install-ros1-peers.sh``) is a skip with its reason.
"""

from __future__ import annotations

import contextlib
import os
import socket
import subprocess
import xmlrpc.client
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from tests.support.env import ROOT, SYSTEM_PYTHON, ros1_missing
from tests.support.procs import (
    Proc,
    free_port,
    master_answers,
    ros_env,
    start_ros1_node,
    wait_for,
)

PEER = ROOT / "tests" / "peers" / "rosbridge"
SETUP = PEER / "setup.sh"
TARBALL = Path(
    os.environ.get(
        "RBS_TARBALL", ROOT.parent / "shared" / "peers" / "rosbridge_suite-0.11.17.tar.gz"
    )
)
#: The system python's modules rosbridge needs beyond ROS 1, and their Debian packages.
APT_MODULES = {
    "twisted": "python3-twisted",
    "autobahn": "python3-autobahn",
    "tornado": "python3-tornado",
    "bson": "python3-bson",
    "PIL": "python3-pil",
}


def rosbridge_missing() -> str | None:
    """Why the real rosbridge_server cannot run here, or None."""
    if reason := ros1_missing():
        return reason
    if not TARBALL.is_file():
        return f"no rosbridge_suite 0.11.17 tarball at {TARBALL} (RBS_TARBALL names one)"
    missing = [
        package
        for module, package in APT_MODULES.items()
        if subprocess.run(
            [SYSTEM_PYTHON, "-c", f"import {module}"], capture_output=True, check=False
        ).returncode
    ]
    if missing:
        return f"rosbridge needs {' '.join(missing)} (scripts/install-ros1-peers.sh installs them)"
    return None


def prepare(scratch: Path) -> dict[str, str]:
    """rosbridge extracted into ``scratch`` and its classes generated: the environment
    additions (``PYTHONPATH``, ``ROS_PACKAGE_PATH``) its processes run with."""
    env = dict(os.environ, RBS_TARBALL=str(TARBALL), PY=SYSTEM_PYTHON)
    done = subprocess.run(
        [str(SETUP), "setup", str(scratch)], env=env, capture_output=True, text=True,
        timeout=300, check=False,
    )  # fmt: skip
    if done.returncode != 0:
        raise AssertionError(f"rosbridge setup failed: {done.stderr[-2000:]}")
    exports = subprocess.run(
        [str(SETUP), "env", str(scratch)], env=env, capture_output=True, text=True, check=True
    ).stdout
    added = {}
    for line in exports.splitlines():
        name, _, value = line.removeprefix("export ").partition("=")
        added[name] = value
    return added


@dataclass
class Rosbridge:
    """A running rosbridge_websocket and rosapi_node."""

    url: str
    port: int
    procs: list[Proc]
    logs: Path

    def log(self) -> str:
        """What both have written so far (for a failing test's message)."""
        return "".join(
            f"--- {p.name}\n{p.read_text(errors='replace')[-4000:]}"
            for p in sorted(self.logs.glob("*.log"))
        )

    def stop(self) -> None:
        """Stop both, by their process groups."""
        for proc in self.procs:
            proc.stop()


def _logged(argv: list[str], env: dict[str, str], log: Path) -> Proc:
    """``argv`` on the system python, stdout and stderr into ``log`` (no pipe to fill)."""
    with log.open("wb") as out:
        # exec keeps the PID: the group stopped is the node's own
        return Proc(["/bin/sh", "-c", 'exec "$0" "$@" 2>&1', *argv], env=env, stdout=out)


def _accepts(port: int) -> bool:
    with contextlib.suppress(OSError), socket.create_connection(("127.0.0.1", port), 0.5):
        return True
    return False


def _registered(master_uri: str, service: str) -> bool:
    try:
        with xmlrpc.client.ServerProxy(master_uri) as master:
            answer: list[object] = master.lookupService("/probe", service)  # type: ignore[assignment]
            return answer[0] == 1
    except (OSError, xmlrpc.client.Error):
        return False


def start_rosbridge(master_uri: str, home: Path) -> Rosbridge:
    """rosapi_node and rosbridge_websocket on ``ws://127.0.0.1:PORT`` (a free port) against
    ``master_uri``, once the port accepts and ``/rosapi/topics`` is registered. Scratch
    files and logs go under ``home``."""
    scratch = home / "rosbridge"
    env = ros_env(master_uri, home) | prepare(scratch)
    src = scratch / "src"
    port = free_port()
    procs: list[Proc] = []
    bridge = Rosbridge(f"ws://127.0.0.1:{port}", port, procs, scratch)
    try:
        procs.append(_logged(
            [SYSTEM_PYTHON, str(src / "rosapi" / "scripts" / "rosapi_node"), "__name:=rosapi"],
            env, scratch / "rosapi.log",
        ))  # fmt: skip
        procs.append(_logged(
            [SYSTEM_PYTHON, str(src / "rosbridge_server" / "scripts" / "rosbridge_websocket"),
             "__name:=rosbridge_websocket", "--address", "127.0.0.1", "--port", str(port)],
            env, scratch / "rosbridge.log",
        ))  # fmt: skip

        def up() -> bool:
            if any(p.popen.poll() is not None for p in procs):
                raise AssertionError(f"rosbridge exited:\n{bridge.log()}")
            return _accepts(port) and _registered(master_uri, "/rosapi/topics")

        wait_for(up, 60, "rosbridge_websocket's port and /rosapi/topics")
    except BaseException:
        bridge.stop()
        raise
    return bridge


def start_rosmaster(home: Path) -> tuple[Proc, str]:
    """The real ``rosmaster --core`` on a free port (no rosout: a graph of the test's nodes
    alone), once it answers: it and its URI."""
    port = free_port()
    uri = f"http://127.0.0.1:{port}"
    env = ros_env(uri, home)
    proc = Proc(["rosmaster", "--core", "-p", str(port)], env=env, stdout=subprocess.DEVNULL)

    def answers() -> bool:
        if proc.popen.poll() is not None:
            raise AssertionError(f"rosmaster exited: {proc.output()[1][-2000:]}")
        return master_answers(uri)

    try:
        wait_for(answers, 30, "rosmaster")
    except BaseException:
        proc.stop()
        raise
    return proc, uri


@contextlib.contextmanager
def rosbridge_graph(master_uri: str, home: Path) -> Iterator[Proc]:
    """``rosbridge_graph.py`` (the tests' rospy node, ``/rbs_ros_side``) on ``master_uri``,
    once registered, while in the ``with``."""
    node = start_ros1_node("rosbridge_graph.py", [], ros_env(master_uri, home))
    try:
        node.expect("ready", 30)
        yield node
    finally:
        node.stop()
