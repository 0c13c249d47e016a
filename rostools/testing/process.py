"""External processes under a test's master: rospy or roscpp nodes, or any command.

Each runs in a session of its own and is stopped through its process group, whose id is
its PID: SIGINT, then SIGTERM, then SIGKILL. Nothing is ever stopped by name, and what a
launcher started (roslaunch, a shell) goes with it. Output goes to a file, so a child
that writes a lot never blocks on a full pipe, and a failed test can show its tail.
If the process that started them dies first (pytest killed by a CI cancel or ``timeout``),
the reaper (``reaper.py``) stops them.
"""

from __future__ import annotations

import atexit
import contextlib
import os
import signal
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

from rostools.errors import NotFoundError
from rostools.rosgraph.masterapi import MasterProxy
from rostools.testing.readable import readable

#: How long ``stop`` waits after SIGINT (rospy usually exits in a fraction of a second).
STOP_WAIT = 3.0
#: Lines of output a report shows.
TAIL_LINES = 20


class _Reaper:
    """The reaper (``reaper.py``) of the process that holds it, started on first use."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.popen: subprocess.Popen[bytes] | None = None
        self.owner = 0  # the PID that started it: a forked child starts its own

    def _started(self) -> subprocess.Popen[bytes]:
        popen = self.popen
        if popen is None or self.owner != os.getpid() or popen.poll() is not None:
            # -I: nothing from the environment or the working folder; it needs only the
            # standard library. Its own session: a Ctrl-C or a group kill meant for pytest
            # leaves it to do its work.
            popen = subprocess.Popen(
                [sys.executable, "-I", str(Path(__file__).with_name("reaper.py"))],
                stdin=subprocess.PIPE,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
                start_new_session=True,
            )
            if self.owner != os.getpid():
                atexit.register(self.close)
            self.popen, self.owner = popen, os.getpid()
        return popen

    def tell(self, line: str) -> None:
        """Send one ``+PGID`` or ``-PGID`` line (a reaper that died is started again)."""
        with self.lock:
            for _ in range(2):
                popen = self._started()
                assert popen.stdin is not None
                try:
                    popen.stdin.write(line.encode() + b"\n")
                    popen.stdin.flush()
                    return
                except OSError:  # it was killed: the next turn starts another
                    popen.wait()

    def close(self) -> None:
        """At exit: close the pipe, so that it stops what is left and exits."""
        with self.lock:
            popen = self.popen
            if popen is None or self.owner != os.getpid():
                return
            assert popen.stdin is not None
            with contextlib.suppress(OSError):
                popen.stdin.close()
            with contextlib.suppress(subprocess.TimeoutExpired):
                popen.wait(10)
            self.popen = None


_REAPER = _Reaper()


def reaper_pid() -> int | None:
    """The PID of this process's reaper, if one runs (for tests)."""
    popen = _REAPER.popen
    return popen.pid if popen is not None and _REAPER.owner == os.getpid() else None


class RosProcess:
    """A child process in its own process group, its output in a file."""

    def __init__(
        self,
        argv: Sequence[str],
        env: Mapping[str, str] | None = None,
        cwd: str | Path | None = None,
        log: str | Path | None = None,
    ) -> None:
        self.argv = [str(a) for a in argv]
        #: Its output once stopped, when the log was a temporary file of ours, now removed.
        self._kept: str | None = None
        self._own_log = log is None
        if log is None:
            handle, name = tempfile.mkstemp(prefix="rostools-proc-", suffix=".log")
            os.close(handle)
            log = name
        self.log = Path(log)
        child_env = dict(os.environ if env is None else env)
        child_env.setdefault("PYTHONUNBUFFERED", "1")  # a Python node's output reaches the log
        with self.log.open("wb") as out:
            self.popen = subprocess.Popen(
                self.argv,
                env=child_env,
                cwd=cwd,
                stdin=subprocess.DEVNULL,
                stdout=out,
                stderr=subprocess.STDOUT,
                start_new_session=True,
            )
        self.pid = self.popen.pid
        _REAPER.tell(f"+{self.pid}")
        self.master_uri = child_env.get("ROS_MASTER_URI", "")

    @property
    def running(self) -> bool:
        """Whether it has not exited."""
        return self.popen.poll() is None

    @property
    def returncode(self) -> int | None:
        """Its exit code, once it has exited (negative: the signal that ended it)."""
        return self.popen.poll()

    def output(self) -> str:
        """Everything it has written so far (stdout and stderr together)."""
        if self._kept is not None:
            return self._kept
        try:
            return self.log.read_bytes().decode(errors="replace")
        except OSError:
            return ""

    def tail(self, lines: int = TAIL_LINES) -> str:
        """The last lines of its output."""
        return "\n".join(self.output().splitlines()[-lines:])

    def _signal(self, sig: int) -> None:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(self.pid, sig)

    def stop(self, timeout: float = STOP_WAIT) -> int:
        """SIGINT, then SIGTERM, then SIGKILL to its process group, until it exits."""
        for sig, wait in ((signal.SIGINT, timeout), (signal.SIGTERM, 1.0)):
            if self.popen.poll() is not None:
                break
            self._signal(sig)
            with contextlib.suppress(subprocess.TimeoutExpired):
                self.popen.wait(wait)
        self._signal(signal.SIGKILL)  # whatever it left behind in its group
        code = self.popen.wait()
        _REAPER.tell(f"-{self.pid}")
        if self._own_log and self._kept is None:  # a temporary log is not left behind
            self._kept = self.output()
            self.log.unlink(missing_ok=True)
        return code

    def _check_alive(self, waiting_for: str) -> None:
        __tracebackhide__ = True
        if self.popen.poll() is not None:
            raise AssertionError(
                f"{self.argv[0]} exited with {self.popen.returncode} before {waiting_for};"
                f" its output:\n{self.tail()}"
            )

    def _wait(self, found: Callable[[MasterProxy], bool], what: str, timeout: float) -> None:
        __tracebackhide__ = True
        master = MasterProxy(self.master_uri, "/rostools_testing", timeout=2.0)
        deadline = time.monotonic() + timeout
        while True:
            self._check_alive(what)
            if found(master):
                return
            if time.monotonic() > deadline:
                raise AssertionError(
                    f"{what} did not appear within {timeout:g} s;"
                    f" {self.argv[0]}'s output:\n{self.tail()}"
                )
            time.sleep(0.02)

    @readable
    def wait_for_node(self, name: str, timeout: float = 10.0) -> RosProcess:
        """Until the master knows node ``name``; fails early if the process exits."""
        __tracebackhide__ = True

        def known(master: MasterProxy) -> bool:
            try:
                master.lookup_node(name)
            except NotFoundError:
                return False
            return True

        self._wait(known, f"node {name}", timeout)
        return self

    @readable
    def wait_for_topic(self, topic: str, timeout: float = 10.0) -> RosProcess:
        """Until ``topic`` has a publisher; fails early if the process exits."""
        __tracebackhide__ = True

        def published(master: MasterProxy) -> bool:
            pubs, _, _ = master.system_state()
            return any(t == topic and nodes for t, nodes in pubs)

        self._wait(published, f"a publisher of {topic}", timeout)
        return self

    def __enter__(self) -> RosProcess:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()


@readable
def start_process(
    argv: Sequence[str],
    *,
    env: Mapping[str, str] | None = None,
    cwd: str | Path | None = None,
    wait_for_node: str | None = None,
    wait_for_topic: str | None = None,
    timeout: float = 10.0,
) -> RosProcess:
    """Start ``argv`` under ``ROS_MASTER_URI``, and wait for its node or topic if asked."""
    __tracebackhide__ = True
    proc = RosProcess(argv, env, cwd)
    try:
        if wait_for_node is not None:
            proc.wait_for_node(wait_for_node, timeout)
        if wait_for_topic is not None:
            proc.wait_for_topic(wait_for_topic, timeout)
    except BaseException:
        proc.stop()
        raise
    return proc
