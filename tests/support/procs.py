"""Processes that tests start: masters, real ROS nodes, rostools commands; and the waits on
what they do (a line printed, a node subscribed, a connection up), so no test sleeps for them.

Every process is started in its own session and stopped by its process group id, which is
its own PID: nothing is ever killed by name, and children of a launcher (roscore starts
rosmaster and rosout) go with it. Each group is also told to the plugin's reaper
(``rostools.testing.reaper``), which stops it if pytest dies first: Ctrl-C in a teardown that
had not stopped them all yet, SIGTERM or SIGKILL to pytest or to an xdist worker.
"""

from __future__ import annotations

import contextlib
import os
import queue
import random
import re
import signal
import socket
import subprocess
import sys
import threading
import time
import xmlrpc.client
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import IO, Any

from tests.support.env import CLI
from tests.support.load import scaled
from tests.support.reap import forget, forget_ended, group_left, reap_with_pytest


def ephemeral_ports() -> tuple[int, int]:
    """The range the kernel hands out to ``bind(0)`` and outgoing connections."""
    try:
        low, high = Path("/proc/sys/net/ipv4/ip_local_port_range").read_text().split()
        return int(low), int(high)
    except (OSError, ValueError):
        return 32768, 60999


def free_port() -> int:
    """A TCP port on loopback that was free a moment ago, below the ephemeral range.

    A port the kernel handed out (``bind(0)``) is handed out again: roscore's roslaunch
    server, started before its master, took the very port chosen for the master (one run
    in a few under load). Ports below the range are never handed out.
    """
    low, _ = ephemeral_ports()
    for _ in range(200):
        port = random.randrange(max(1024, low - 12000), low)
        with socket.socket() as s:
            try:
                s.bind(("127.0.0.1", port))
            except OSError:
                continue
            return port
    with socket.socket() as s:  # all taken: any the kernel gives
        s.bind(("127.0.0.1", 0))
        chosen: int = s.getsockname()[1]
        return chosen


@contextlib.contextmanager
def silent_port() -> Iterator[int]:
    """A loopback port that accepts connections and never answers, while in the ``with``."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        sock.listen(16)
        port: int = sock.getsockname()[1]
        yield port


def wait_for(
    predicate: Callable[[], object],
    timeout: float = 10.0,
    what: str = "condition",
    interval: float = 0.05,
) -> None:
    """Poll ``predicate`` every ``interval`` s until true; AssertionError after ``timeout`` s
    (on a quiet machine: the run's load factor scales it, ``tests/support/load.py``)."""
    timeout = scaled(timeout)
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if predicate():
            return
        time.sleep(interval)
    raise AssertionError(f"timed out after {timeout:.3g} s waiting for {what}")


def until_printed(act: Callable[[], object], node: Proc, seen: str, timeout: float = 30) -> None:
    """Do ``act`` until ``node`` prints ``seen`` (a subscriber may connect after the first)."""

    def printed() -> bool:
        act()
        try:
            node.expect(seen, 0.5)
        except AssertionError:
            return False
        return True

    wait_for(printed, timeout, f"{seen!r} to be printed")


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


def _graph(master_uri: str, kind: int, topic: str) -> list[str]:
    with xmlrpc.client.ServerProxy(master_uri) as proxy:
        state = proxy.getSystemState("/probe")[2][kind]
    return next((list(names) for t, names in state if t == topic), [])


def publishers(master_uri: str, topic: str) -> list[str]:
    """The nodes the master lists as publishers of ``topic``."""
    return _graph(master_uri, 0, topic)


def subscribers(master_uri: str, topic: str) -> list[str]:
    """The nodes the master lists as subscribers of ``topic``."""
    return _graph(master_uri, 1, topic)


def subscribed(master_uri: str, topic: str, prefix: str) -> bool:
    """Whether a node whose name starts with ``prefix`` subscribes to ``topic``."""
    return any(name.startswith(prefix) for name in subscribers(master_uri, topic))


def linked(master_uri: str, node: str, topic: str) -> list[str]:
    """The peers ``node`` has a live connection with on ``topic``, from its ``getBusInfo``.

    A publisher names each subscriber (its caller id), a subscriber each publisher's URI. A
    publisher lists a subscriber once its reply header is sent: what it publishes from then
    on reaches that subscriber, which the master's lists alone do not tell.
    """
    try:
        with xmlrpc.client.ServerProxy(master_uri) as master:
            code, _, uri = master.lookupNode("/probe", node)
        if code != 1:
            return []
        with xmlrpc.client.ServerProxy(uri) as peer:
            entries: list[Any] = peer.getBusInfo("/probe")[2]
    except (OSError, xmlrpc.client.Error):
        return []  # gone, or not up yet
    return [str(e[1]) for e in entries if e[4] == topic and e[5]]


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
        reap_with_pytest(self.pid, self._may_run)
        #: Stream name -> the lines read from it and not yet looked at.
        self._lines: dict[str, queue.Queue[str]] = {}
        self._readers: list[threading.Thread] = []
        #: The stdout lines ``expect`` has looked at, in order.
        self.seen: list[str] = []
        #: The stderr lines ``expect(..., stderr=True)`` has looked at, in order.
        self.seen_err: list[str] = []

    def _may_run(self) -> bool:
        """Whether it, or anything left in its group, may still run."""
        return self.popen.poll() is None or group_left(self.pid)

    def expect(self, pattern: str, timeout: float = 15.0, *, stderr: bool = False) -> str:
        """The next stdout (or stderr) line matching the regex ``pattern``.

        AssertionError after ``timeout`` seconds without one (scaled by the run's load factor).
        """
        timeout = scaled(timeout)
        self._start_readers()
        name, seen = ("stderr", self.seen_err) if stderr else ("stdout", self.seen)
        lines = self._lines[name]
        deadline = time.monotonic() + timeout
        while (left := deadline - time.monotonic()) > 0:
            try:
                line = lines.get(timeout=left)
            except queue.Empty:
                break
            seen.append(line)
            if re.search(pattern, line):
                return line
        tail = "".join(seen[-10:])
        raise AssertionError(
            f"{self.argv[:3]} printed no line matching {pattern!r}; last: {tail!r}"
        )

    def _start_readers(self) -> None:
        """Read both pipes in threads from now on (one read alone could fill the other)."""
        if self._readers:
            return
        for name in ("stdout", "stderr"):
            stream = getattr(self.popen, name)
            if stream is not None:
                self._lines[name] = queue.Queue()
                reader = threading.Thread(target=self._read, args=(name, stream), daemon=True)
                reader.start()
                self._readers.append(reader)

    def _read(self, name: str, stream: IO[bytes]) -> None:
        for raw in stream:
            self._lines[name].put(raw.decode(errors="replace"))

    def signal(self, sig: int) -> None:
        """Send ``sig`` to the process group."""
        with contextlib.suppress(ProcessLookupError):
            os.killpg(self.pid, sig)

    #: How long ``stop`` waits after each of SIGINT and SIGTERM.
    stop_timeout = 5.0

    def stop(self, timeout: float | None = None) -> int:
        """SIGINT, then SIGTERM, then SIGKILL, until it and its group exit; its return code.

        A launcher's children finish after it: ``rosbag record`` (Python) exits before the
        ``record`` it started has closed its file, and killing that one then left the file
        ``.active`` (one run in six). So each signal waits for the whole group.
        """
        timeout = scaled(self.stop_timeout if timeout is None else timeout)
        for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGKILL):
            if self.popen.poll() is not None:  # exited before: its group ends on its own
                self._wait_group(timeout)
                break
            self.signal(sig)
            if self._wait_group(timeout):
                break
        self.signal(signal.SIGKILL)  # anything the launcher left behind in its group
        code = self.popen.wait()
        forget(self.pid)
        for reader in self._readers:  # at the pipes' end by now; closed under it, it would raise
            reader.join(1)
        for stream in (self.popen.stdout, self.popen.stderr):
            if stream is not None:
                stream.close()
        return code

    def _wait_group(self, timeout: float) -> bool:
        """Whether it and every process of its group exit within ``timeout`` seconds."""
        deadline = time.monotonic() + timeout
        while self.popen.poll() is None or group_members(self.pid):
            if time.monotonic() >= deadline:
                return False
            time.sleep(0.02)
        return True

    def output(self) -> tuple[str, str]:
        """Everything it wrote on stdout and stderr, once it has exited (``expect``'s lines too)."""
        if not self._readers:
            out, err = self.popen.communicate(timeout=30)
            return (out or b"").decode(errors="replace"), (err or b"").decode(errors="replace")
        self.popen.wait(30)
        for reader in self._readers:
            reader.join(30)
        for name, seen in (("stdout", self.seen), ("stderr", self.seen_err)):
            lines = self._lines.get(name)
            while lines is not None and not lines.empty():
                seen.append(lines.get_nowait())
        return "".join(self.seen), "".join(self.seen_err)


@contextlib.contextmanager
def cpu_hogs(count: int = 2) -> Iterator[list[Proc]]:
    """``count`` processes spinning at normal priority while in the ``with``: a busy machine.

    Each has said it spins before the body runs; each is stopped by its PID at the end.
    """
    code = "print('spinning', flush=True)\nwhile True: pass"
    hogs: list[Proc] = []
    try:
        for _ in range(count):
            hogs.append(Proc([sys.executable, "-c", code]))
        for hog in hogs:
            hog.expect("spinning")
        yield hogs
    finally:
        for hog in hogs:
            hog.stop()


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


def start_cli(
    *args: str,
    env: dict[str, str],
    cwd: Path | None = None,
    stdin: int | None = subprocess.DEVNULL,
) -> Proc:
    """``rostools ARGS`` as a child of its own, left running (``run_cli`` runs one to its end)."""
    return Proc([*CLI, *args], env=env, cwd=cwd, stdin=stdin)


def start_rostools_core(port: int, env: dict[str, str]) -> Proc:
    """``rostools core --port PORT``, once it answers."""
    proc = start_cli("core", "--port", str(port), env=env)
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
        forget_ended()
        return code

    def reap_children(self) -> None:
        """Tell the reaper the groups of the children it runs now (rosmaster, rosout)."""
        for pid in child_pids(self.pid):
            with contextlib.suppress(ProcessLookupError):
                if (group := os.getpgid(pid)) != self.pid:
                    reap_with_pytest(group)


def group_members(group: int) -> list[int]:
    """The PIDs of the live processes (zombies aside) in process group ``group`` (``/proc``)."""
    members = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        with contextlib.suppress(OSError, IndexError, ValueError):
            # after "(command)": state, the parent's PID, then the process group
            fields = stat.read_text().rsplit(")", 1)[1].split()
            if int(fields[2]) == group and fields[0] != "Z":
                members.append(int(stat.parent.name))
    return members


def child_pids(parent: int) -> list[int]:
    """The PIDs of ``parent``'s children (Linux ``/proc``)."""
    children = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        with contextlib.suppress(OSError, IndexError, ValueError):
            # after "(command)": state, then the parent's PID
            if int(stat.read_text().rsplit(")", 1)[1].split()[1]) == parent:
                children.append(int(stat.parent.name))
    return children


def start_roscore(port: int, env: dict[str, str], *, launch: bool = False) -> Proc:
    """A real ROS 1 core on ``port``, once its master answers.

    ``roscore`` is roslaunch starting ``rosmaster --core``, setting ``/run_id``,
    ``/rosversion`` and ``/rosdistro``, and starting ``rosout``. Without ``launch`` those real
    parts are started here as roslaunch starts them, without roslaunch, which takes 3 to 5
    s of a loaded machine to start (105 tests start a core). With ``launch``, ``roscore -p``.
    """
    proc = Roscore(["roscore", "-p", str(port)], env=env) if launch else CoreParts(port, env)
    uri = f"http://127.0.0.1:{port}/"
    wait_for(lambda: master_answers(uri) or proc.popen.poll() is not None, 30, "roscore")
    if proc.popen.poll() is not None:
        raise AssertionError(f"roscore exited: {proc.output()}")
    if isinstance(proc, CoreParts):
        proc.start_rosout(uri)
    else:
        # a roscore killed with pytest would stop them in its own time, past the reaper's grace
        proc.reap_children()
    return proc


class CoreParts(Proc):
    """``rosmaster --core``, then roscore's parameters and ``rosout``, as roslaunch starts them.

    Each runs in a process group of its own, as under roscore; ``stop`` stops both.
    """

    def __init__(self, port: int, env: dict[str, str]) -> None:
        import uuid

        self.env = env
        self.run_id = str(uuid.uuid1())
        home = Path(env.get("ROS_HOME", Path.home() / ".ros"))
        self.logs = Path(env.get("ROS_LOG_DIR", home / "log")) / self.run_id
        argv = ["rosmaster", "--core", "-p", str(port), "-w", "3"]
        super().__init__([*argv, f"__log:={self.logs / 'master.log'}"], env=env)
        self.rosout: Proc | None = None

    def start_rosout(self, uri: str) -> None:
        """roscore's parameters (as roslaunch sets them, before its nodes), then ``rosout``."""
        with xmlrpc.client.ServerProxy(uri) as master:
            master.setParam("/roslaunch", "/run_id", self.run_id)
            for name, value in _ros_versions().items():
                master.setParam("/roslaunch", name, value)
        log = f"__log:={self.logs / 'rosout-1.log'}"
        self.rosout = Proc(["/usr/lib/rosout/rosout", "__name:=rosout", log], env=self.env)

    def stop(self, timeout: float | None = 0) -> int:
        """SIGKILL rosout and the master (no test checks roscore's own shutdown)."""
        if self.rosout is not None:
            self.rosout.stop(timeout)
        return super().stop(timeout)


_versions: dict[str, str] = {}


def _ros_versions() -> dict[str, str]:
    """``/rosversion`` and ``/rosdistro`` as roslaunch sets them (``rosversion``), asked once."""
    if not _versions:
        for name, args in (("/rosversion", ["roslaunch"]), ("/rosdistro", ["-d"])):
            done = subprocess.run(["rosversion", *args], capture_output=True, text=True, check=True)
            _versions[name] = done.stdout.strip() + "\n"
    return _versions


NODES = Path(__file__).with_name("ros1_nodes")


def start_ros1_node(script: str, args: Sequence[str], env: dict[str, str]) -> Proc:
    """One of ``tests/support/ros1_nodes`` on the system python (real rospy)."""
    proc = Proc(["/usr/bin/python3", str(NODES / script), *args], env=env)
    # A rospy publisher with a subscriber connected can hang in its shutdown, deaf to SIGINT
    # and SIGTERM (seen here: 10 s each time, until SIGKILL); nothing of it is checked then.
    proc.stop_timeout = 1.0
    return proc
