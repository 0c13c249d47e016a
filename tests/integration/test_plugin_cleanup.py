"""The pytest plugin's processes die with pytest, even when pytest is killed outright.

A CI cancel or ``timeout`` sends SIGTERM, then SIGKILL; neither runs a fixture's teardown,
and ``ros_process`` children live in sessions of their own. A suite run here starts some
(a sleeper, a launcher with a child in its group, one started from a thread that then ends,
``rostools core``), writes their PIDs down and waits; this test kills that pytest by its PID
and checks by PID that every one of them is gone.
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

from tests.support.procs import free_port, master_answers, wait_for

SUITE = """
import json, os, sys, threading, time
from pathlib import Path

from rostools.testing.process import reaper_pid

SLEEP = [sys.executable, "-c", "import time; time.sleep(600)"]


def test_start_and_wait(ros_master, ros_process, tmp_path):
    grandchild = tmp_path / "grandchild"
    procs = [
        ros_process(SLEEP),
        # a launcher: its child stays in the launcher's process group
        ros_process(["sh", "-c", f"sleep 600 & echo $! > {grandchild}; wait"]),
        ros_process([sys.executable, "-m", "rostools", "core", "--port", os.environ["CORE_PORT"]]),
    ]
    # started from a thread that then ends (PR_SET_PDEATHSIG would kill it right here)
    thread = threading.Thread(target=lambda: procs.append(ros_process(SLEEP)))
    thread.start()
    thread.join()
    while not grandchild.exists() or not grandchild.read_text().strip():
        time.sleep(0.02)
    time.sleep(0.3)
    assert all(p.running for p in procs)
    info = {
        "pytest": os.getpid(),
        "reaper": reaper_pid(),
        "children": [p.pid for p in procs] + [int(grandchild.read_text())],
        "master": ros_master.uri,
    }
    tmp = Path(os.environ["INFO_FILE"] + ".tmp")
    tmp.write_text(json.dumps(info))
    tmp.replace(os.environ["INFO_FILE"])
    time.sleep(600)
"""


def alive(pid: int) -> bool:
    """Whether ``pid`` runs (a zombie does not: this machine's PID 1 may never reap it)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return False
    return state not in "ZX"


class Run:
    """A pytest run of ``SUITE`` in its own session, and what it reported."""

    def __init__(self, folder: Path, extra: list[str]) -> None:
        self.info_file = folder / "info.json"
        (folder / "test_suite.py").write_text(SUITE)
        env = dict(os.environ, INFO_FILE=str(self.info_file), CORE_PORT=str(free_port()))
        self.log = folder / "pytest.log"
        with self.log.open("wb") as out:
            self.popen = subprocess.Popen(
                [sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-p", "no:randomly",
                 "-q", *extra, "test_suite.py"],
                cwd=folder, env=env, stdout=out, stderr=subprocess.STDOUT,
                start_new_session=True,
            )  # fmt: skip
        self.info: dict[str, object] = {}

    def wait_for_info(self) -> dict[str, object]:
        """What the suite wrote down once all its processes run."""
        wait_for(lambda: self.info_file.exists() or self.popen.poll() is not None, 60, "the suite")
        assert self.info_file.exists(), self.log.read_text()[-3000:]
        self.info = json.loads(self.info_file.read_text())
        return self.info

    def pids(self) -> list[int]:
        """Every process the suite started, with its reaper."""
        children = self.info.get("children", [])
        assert isinstance(children, list)
        reaper = self.info.get("reaper")
        return [int(p) for p in children] + ([int(reaper)] if isinstance(reaper, int) else [])

    def stop(self) -> None:
        """Whatever is left, by PID: pytest, its workers and every process it wrote down."""
        for pid in [self.popen.pid, *self.pids()]:
            if alive(pid):
                with contextlib.suppress(ProcessLookupError):
                    os.kill(pid, signal.SIGKILL)
        self.popen.wait(10)


@pytest.fixture
def run() -> Iterator[list[Run]]:
    """The runs a test starts, stopped after it by their PIDs."""
    runs: list[Run] = []
    yield runs
    for started in runs:
        started.stop()


@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGTERM], ids=["SIGKILL", "SIGTERM"])
@pytest.mark.parametrize("xdist", [False, True], ids=["plain", "xdist"])
def test_killing_pytest_stops_every_process_it_started(
    sig: signal.Signals, xdist: bool, run: list[Run], tmp_path: Path
) -> None:
    started = Run(tmp_path, ["-p", "xdist", "-n", "1"] if xdist else [])
    run.append(started)
    info = started.wait_for_info()
    children = started.pids()[:-1]
    assert len(children) == 5 and all(alive(p) for p in children)
    reaper = info["reaper"]
    assert isinstance(reaper, int) and alive(reaper)
    # under xdist the processes belong to the worker, which is what a killed run loses
    victim = info["pytest"]
    assert isinstance(victim, int) and (victim != started.popen.pid) == xdist
    os.kill(victim, sig)
    wait_for(lambda: not any(alive(p) for p in children), 15, "the suite's processes to stop")
    wait_for(lambda: not alive(reaper), 10, "the reaper to exit")
    # the test's master ran inside pytest, so it went with it
    assert isinstance(info["master"], str) and not master_answers(info["master"])


def test_a_finished_run_leaves_no_reaper(tmp_path: Path) -> None:
    (tmp_path / "test_one.py").write_text(
        "import os, sys\n"
        "from pathlib import Path\n"
        "from rostools.testing.process import reaper_pid\n"
        "def test_one(ros_process):\n"
        "    ros_process([sys.executable, '-c', 'import time; time.sleep(600)'])\n"
        "    Path(os.environ['REAPER_FILE']).write_text(str(reaper_pid()))\n"
    )
    env = dict(os.environ, REAPER_FILE=str(tmp_path / "reaper"))
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-q", "test_one.py"],
        cwd=tmp_path, env=env, capture_output=True, text=True, timeout=60, check=False,
    )  # fmt: skip
    assert done.returncode == 0, done.stdout[-3000:]
    reaper = int((tmp_path / "reaper").read_text())
    assert not alive(reaper)  # pytest waited for it at exit
