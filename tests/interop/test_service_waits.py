"""``service call`` waits as long as rosservice does: no limit unless ``--timeout`` says so.

A slow handler (map saving, calibration, a simulator starting) took longer than our old 10 s
default, and the call failed with exit 5 while the server still ran it. Both tools run side
by side here, against the same rospy server.
"""

from __future__ import annotations

import subprocess
import time
from pathlib import Path

import pytest

from tests.conftest import MasterInfo
from tests.support.env import CLI, needs_ros1, run_cli
from tests.support.procs import ros_env, start_ros1_node, wait_for
from tests.support.reap import reap_with_pytest

pytestmark = [pytest.mark.interop, needs_ros1]

#: Just past the old default of 10 s.
SLOW = 10.5
WAITING = "rostools: waiting for service /slow to respond (3 s so far; Ctrl-C stops, --timeout "


def _both(info: MasterInfo, *argv: str) -> tuple[subprocess.Popen[str], subprocess.Popen[str]]:
    """``rostools service ARGV`` and ``rosservice ARGV``, started together."""
    pipes = {"stdout": subprocess.PIPE, "stderr": subprocess.PIPE, "text": True}
    ours = subprocess.Popen([*CLI, "service", *argv], env=info.cli_env, **pipes,
                            start_new_session=True)  # fmt: skip
    reap_with_pytest(ours.pid)
    theirs = subprocess.Popen(["rosservice", *argv], env=info.ros_env, **pipes,
                              start_new_session=True)  # fmt: skip
    reap_with_pytest(theirs.pid)
    return ours, theirs


def test_a_slow_service_is_waited_for(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    info = MasterInfo("rostools", rostools_master, ros_env(rostools_master, tmp_path), cli_env)
    server = start_ros1_node("add_two_ints_server.py", [str(SLOW)], info.ros_env)
    try:
        server.expect("ready", 30)
        wait_for(lambda: "/slow" in run_cli("service", "list", env=cli_env).stdout, 20, "/slow")
        ours, theirs = _both(info, "call", "/slow")
        out, err = ours.communicate(timeout=60)
        their_out, their_err = theirs.communicate(timeout=60)
        assert (ours.returncode, theirs.returncode) == (0, 0), (err, their_err)
        assert out == their_out == 'success: True\nmessage: "slowly"\n'
        assert err.startswith(WAITING), err  # said once, what it waits for
        assert err.count("\n") == 1
        started = time.monotonic()
        bounded = run_cli("service", "call", "/slow", "--timeout", "1", env=cli_env)
        assert bounded.returncode == 5
        assert bounded.stderr == "rostools: service /slow did not respond within 1 s\n"
        assert time.monotonic() - started < SLOW  # gave up before the answer could come
    finally:
        server.stop()


def test_wait_waits_for_the_service_to_appear(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    info = MasterInfo("rostools", rostools_master, ros_env(rostools_master, tmp_path), cli_env)
    ours, theirs = _both(info, "call", "--wait", "/trigger")
    server = None
    try:
        time.sleep(4)  # the wait is the behaviour under test: past the 3 s notice
        assert ours.poll() is None and theirs.poll() is None
        server = start_ros1_node("add_two_ints_server.py", [], info.ros_env)
        out, err = ours.communicate(timeout=60)
        their_out, their_err = theirs.communicate(timeout=60)
    finally:
        for proc in (ours, theirs):
            if proc.poll() is None:
                proc.kill()
                proc.wait()
        if server is not None:
            server.stop()
    assert (ours.returncode, theirs.returncode) == (0, 0), (err, their_err)
    assert out.startswith("success: True") and their_out.startswith("success: True")
    assert err.startswith("rostools: waiting for service /trigger to appear (3 s so far;"), err
