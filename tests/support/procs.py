"""Processes that tests start: masters, real ROS nodes, rostools commands.

Every process is started in its own session and stopped by its process group id, which is
its own PID: nothing is ever killed by name, and children of a launcher (roscore starts
rosmaster and rosout) go with it.
"""

from __future__ import annotations

import contextlib
import os
import queue
import re
import signal
import socket
import subprocess
import sys
import threading
import time
import xmlrpc.client
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import IO


def free_port() -> int:
    """A TCP port on loopback that was free a moment ago."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port: int = s.getsockname()[1]
        return port


def wait_for(predicate: Callable[[], bool], timeout: float = 10.0, what: str = "condition") -> None:
    """Poll ``predicate`` until it is true; AssertionError after ``timeout`` seconds."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(0.05)
    raise AssertionError(f"timed out after {timeout} s waiting for {what}")


def wait_for_name(names: Callable[[], list[str]], suffix: str, timeout: float = 15.0) -> str:
    """The first of ``names()`` that ends with ``suffix``, polling until there is one."""
    found: list[str] = []

    def listed() -> bool:
        found[:] = [n for n in names() if n.endswith(suffix)]
        return bool(found)

    wait_for(listed, timeout, f"a name ending in {suffix}")
    return found[0]


def master_answers(uri: str) -> bool:
    """Whether an XML-RPC master answers ``getPid`` at ``uri``."""
    try:
        with xmlrpc.client.ServerProxy(uri) as proxy:
            return bool(proxy.getPid("/probe")[0] == 1)
    except (OSError, xmlrpc.client.Error):
        return False


class Proc:
    """A child process in its own process group."""

    def __init__(
        self,
        argv: Sequence[str],
        env: dict[str, str] | None = None,
        cwd: Path | None = None,
        stdout: int | IO[bytes] | None = subprocess.PIPE,
        stdin: int | None = subprocess.DEVNULL,
    ) -> None:
        self.argv = list(argv)
        self.popen = subprocess.Popen(
            self.argv,
            env=env,
            cwd=cwd,
            stdin=stdin,
            stdout=stdout,
            stderr=subprocess.PIPE,
            start_new_session=True,
        )
        self.pid = self.popen.pid
        self._lines: queue.Queue[str] | None = None
        self.seen: list[str] = []

    def expect(self, pattern: str, timeout: float = 15.0) -> str:
        """The next stdout line matching the regex ``pattern``; AssertionError on timeout."""
        if self._lines is None:
            self._lines = queue.Queue()
            threading.Thread(target=self._read, daemon=True).start()
        deadline = time.monotonic() + timeout
        while (left := deadline - time.monotonic()) > 0:
            try:
                line = self._lines.get(timeout=left)
            except queue.Empty:
                break
            self.seen.append(line)
            if re.search(pattern, line):
                return line
        tail = "".join(self.seen[-10:])
        raise AssertionError(
            f"{self.argv[:3]} printed no line matching {pattern!r}; last: {tail!r}"
        )

    def _read(self) -> None:
        assert self.popen.stdout is not None and self._lines is not None
        for raw in self.popen.stdout:
            self._lines.put(raw.decode(errors="replace"))

    def signal(self, sig: int) -> None:
        """Send ``sig`` to the process group."""
        with contextlib.suppress(ProcessLookupError):
            os.killpg(self.pid, sig)

    #: How long ``stop`` waits after each of SIGINT and SIGTERM.
    stop_timeout = 5.0

    def stop(self, timeout: float | None = None) -> int:
        """SIGINT, then SIGTERM, then SIGKILL, until it exits; its return code."""
        timeout = self.stop_timeout if timeout is None else timeout
        for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGKILL):
            if self.popen.poll() is not None:
                break
            self.signal(sig)
            try:
                self.popen.wait(timeout)
            except subprocess.TimeoutExpired:
                continue
        self.signal(signal.SIGKILL)  # anything the launcher left behind in its group
        code = self.popen.wait()
        for stream in (self.popen.stdout, self.popen.stderr):
            if stream is not None:
                stream.close()
        return code

    def output(self) -> tuple[str, str]:
        """Everything it wrote, once it has exited."""
        out, err = self.popen.communicate(timeout=30)
        return (out or b"").decode(errors="replace"), (err or b"").decode(errors="replace")


def ros_env(master_uri: str, home: Path) -> dict[str, str]:
    """An environment for a real ROS 1 process on ``master_uri``, logs kept under ``home``."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS")}
    env.update(
        ROS_MASTER_URI=master_uri,
        ROS_HOME=str(home),
        ROS_LOG_DIR=str(home / "log"),
        ROS_IP="127.0.0.1",
        PYTHONUNBUFFERED="1",
    )
    return env


def start_rostools_core(port: int, env: dict[str, str]) -> Proc:
    """``rostools core --port PORT``, once it answers."""
    proc = Proc([sys.executable, "-m", "rostools", "core", "--port", str(port)], env=env)
    uri = f"http://127.0.0.1:{port}/"
    wait_for(lambda: master_answers(uri) or proc.popen.poll() is not None, 15, "rostools core")
    if proc.popen.poll() is not None:
        raise AssertionError(f"rostools core exited: {proc.output()[1]}")
    return proc


def core_and_env(home: Path) -> tuple[Proc, dict[str, str]]:
    """``rostools core`` on a free port, and an environment for rostools children on it.

    The environment inherits no ROS settings: a private HOME under ``home``, the built-in
    types only, and loopback addresses.
    """
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS")}
    port = free_port()
    env |= {"HOME": str(home / "home"), "ROS_PACKAGE_PATH": "", "ROS_IP": "127.0.0.1"}
    env["ROS_MASTER_URI"] = f"http://127.0.0.1:{port}"
    return start_rostools_core(port, env), env


class Roscore(Proc):
    """``roscore``, whose rosmaster and rosout run in process groups of their own."""

    def stop(self, timeout: float | None = 0) -> int:
        """SIGKILL roscore, then its children, which it would leave running.

        No test checks roscore's own shutdown, which takes a second; 61 tests start one.
        """
        # stopped first, so that it starts no child (rosout) between the look and the kill:
        # one started in that moment outlived its test by hours
        with contextlib.suppress(ProcessLookupError):
            os.kill(self.pid, signal.SIGSTOP)
        children = child_pids(self.pid)
        code = super().stop(timeout)
        for pid in children:
            with contextlib.suppress(ProcessLookupError):
                os.kill(pid, signal.SIGKILL)
        return code


def child_pids(parent: int) -> list[int]:
    """The PIDs of ``parent``'s children (Linux ``/proc``)."""
    children = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        with contextlib.suppress(OSError, IndexError, ValueError):
            # after "(command)": state, then the parent's PID
            if int(stat.read_text().rsplit(")", 1)[1].split()[1]) == parent:
                children.append(int(stat.parent.name))
    return children


def start_roscore(port: int, env: dict[str, str]) -> Proc:
    """The real ``roscore -p PORT`` (master and rosout), once the master answers."""
    proc = Roscore(["roscore", "-p", str(port)], env=env)
    uri = f"http://127.0.0.1:{port}/"
    wait_for(lambda: master_answers(uri) or proc.popen.poll() is not None, 30, "roscore")
    if proc.popen.poll() is not None:
        raise AssertionError(f"roscore exited: {proc.output()}")
    return proc


NODES = Path(__file__).with_name("ros1_nodes")


def start_ros1_node(script: str, args: Sequence[str], env: dict[str, str]) -> Proc:
    """One of ``tests/support/ros1_nodes`` on the system python (real rospy)."""
    proc = Proc(["/usr/bin/python3", str(NODES / script), *args], env=env)
    # A rospy publisher with a subscriber connected can hang in its shutdown, deaf to SIGINT
    # and SIGTERM (seen here: 10 s each time, until SIGKILL); nothing of it is checked then.
    proc.stop_timeout = 1.0
    return proc
