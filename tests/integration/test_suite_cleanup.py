"""The suite's own processes die with pytest: Ctrl-C, SIGTERM or SIGKILL, with xdist or without.

The plugin's ``ros_process`` children had a reaper; the suite's helpers (``Proc``, ``run_cli``)
did not, and a Ctrl-C that reached pytest while a fixture was stopping its processes one by
one left the rest running (a ``topic pub`` and ``rt_services.py`` were found 38 minutes on).
A small suite run here starts a master, a ``topic pub``, ``rt_services.py``, a process slow to
stop and a ``topic echo`` through ``run_cli``, writes their PIDs down, and is interrupted;
every one of them must be gone soon after, checked by PID.
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.integration.test_plugin_cleanup import alive
from tests.support.env import ROOT
from tests.support.procs import wait_for

SUITE = """
import json, os, sys, threading, time
from pathlib import Path

import pytest

from tests.support.env import ROOT, run_cli
from tests.support.procs import Proc, child_pids, core_and_env, publishers, start_cli, wait_for

INFO = Path(os.environ["INFO_FILE"])
#: ignores SIGINT, so that stopping it takes a while (Proc.stop waits before SIGTERM)
SLOW = "import signal, time; signal.signal(signal.SIGINT, signal.SIG_IGN); time.sleep(600)"
PIDS = []


def note(stage):
    tmp = INFO.with_suffix(".tmp")
    tmp.write_text(json.dumps({"stage": stage, "pytest": os.getpid(), "pids": PIDS}))
    tmp.replace(INFO)


@pytest.fixture
def graph(tmp_path):
    core, env = core_and_env(tmp_path)
    procs = [
        Proc([sys.executable, "-c", SLOW]),
        start_cli("topic", "pub", "-r", "5", "/chatter", "std_msgs/String", "data: hi", env=env),
        Proc([sys.executable, str(ROOT / "tests/support/rt_nodes/rt_services.py")], env=env),
    ]
    PIDS.extend([core.pid] + [p.pid for p in procs])
    try:
        yield env
    finally:
        note("teardown")
        for proc in procs:
            proc.stop()
        core.stop()


def test_graph(graph):
    master = graph["ROS_MASTER_URI"]
    wait_for(lambda: publishers(master, "/chatter"), 60, "the publisher")
    wait_for(lambda: run_cli("service", "list", env=graph).stdout.count("/add_two_ints"), 60,
             "the services")
    # a command run to its end that does not end by itself
    threading.Thread(
        target=run_cli, args=("topic", "echo", "/nothing"), kwargs={"env": graph, "timeout": 900},
        daemon=True,
    ).start()

    def echo():
        for pid in child_pids(os.getpid()):
            with open(f"/proc/{pid}/cmdline", "rb") as cmdline:
                if b"echo" in cmdline.read():
                    return pid
        return None

    wait_for(echo, 60, "topic echo")
    PIDS.append(echo())
    note("running")
    if os.environ["WHEN"] == "body":
        time.sleep(600)
"""


class Run:
    """A pytest run of ``SUITE`` in its own session (its process group: a terminal's)."""

    def __init__(self, folder: Path, xdist: bool, when: str) -> None:
        self.info_file = folder / "info.json"
        (folder / "test_suite.py").write_text(SUITE)
        env = dict(os.environ, INFO_FILE=str(self.info_file), WHEN=when, PYTHONPATH=str(ROOT))
        self.log = folder / "pytest.log"
        with self.log.open("wb") as out:
            self.popen = subprocess.Popen(
                [sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-q",
                 *(["-p", "xdist", "-n", "1"] if xdist else []), "test_suite.py"],
                cwd=folder, env=env, stdout=out, stderr=subprocess.STDOUT,
                start_new_session=True,
            )  # fmt: skip
        self.info: dict[str, object] = {}

    def wait_for(self, stage: str) -> list[int]:
        """Until the suite is at ``stage``; the PIDs of every process it started, pytest's too."""

        def there() -> bool:
            if self.popen.poll() is not None:
                return True
            with contextlib.suppress(OSError, ValueError):
                self.info = json.loads(self.info_file.read_text())
            return self.info.get("stage") == stage

        wait_for(there, 120, f"the suite to reach its {stage}")
        assert self.info.get("stage") == stage, self.log.read_text()[-3000:]
        pids = self.info["pids"]
        assert isinstance(pids, list) and len(pids) == 5
        assert all(alive(pid) for pid in pids)
        return [int(pid) for pid in pids]

    def stop(self) -> None:
        """Whatever is left, by PID."""
        pids = self.info.get("pids", [])
        assert isinstance(pids, list)
        for pid in [self.popen.pid, self.info.get("pytest"), *pids]:
            if isinstance(pid, int) and alive(pid):
                with contextlib.suppress(ProcessLookupError):
                    os.kill(pid, signal.SIGKILL)
        self.popen.wait(30)


@pytest.fixture
def runs() -> Iterator[list[Run]]:
    """The runs a test starts, stopped after it by their PIDs."""
    started: list[Run] = []
    yield started
    for run in started:
        run.stop()


@pytest.mark.parametrize("xdist", [False, True], ids=["plain", "xdist"])
def test_ctrl_c_while_a_fixture_stops_its_processes(
    xdist: bool, runs: list[Run], tmp_path: Path
) -> None:
    run = Run(tmp_path, xdist, "teardown")
    runs.append(run)
    pids = run.wait_for("teardown")  # stopping the slow one first: the rest still run
    os.killpg(run.popen.pid, signal.SIGINT)  # a terminal's Ctrl-C reaches its whole group
    wait_for(lambda: not any(alive(p) for p in pids), 30, "the suite's processes to stop")
    assert run.popen.wait(30) != 0


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGKILL], ids=["SIGTERM", "SIGKILL"])
@pytest.mark.parametrize("xdist", [False, True], ids=["plain", "xdist"])
def test_pytest_killed_mid_test(
    sig: signal.Signals, xdist: bool, runs: list[Run], tmp_path: Path
) -> None:
    run = Run(tmp_path, xdist, "body")
    runs.append(run)
    pids = run.wait_for("running")
    os.kill(run.popen.pid, sig)  # pytest alone, as `kill PID` or a CI runner sends it
    wait_for(lambda: not any(alive(p) for p in pids), 30, "the suite's processes to stop")
    worker = run.info["pytest"]
    assert isinstance(worker, int)
    wait_for(lambda: not alive(worker), 30, "pytest to exit")


def test_ctrl_c_reaches_the_tests_processes_when_pytest_was_started_ignoring_it() -> None:
    """A script's ``pytest &`` starts it with SIGINT ignored, which every child inherited: the
    tests of what Ctrl-C does failed (six in a run started so)."""
    test = "tests/integration/test_exit_codes.py::test_interrupted_wait_is_130"
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-n", "0", test],
        cwd=ROOT, capture_output=True, text=True, timeout=300, check=False,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_IGN),
    )  # fmt: skip
    assert done.returncode == 0, done.stdout[-2000:]
