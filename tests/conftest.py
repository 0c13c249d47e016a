"""Shared fixtures."""

from __future__ import annotations

import os
import signal
from collections.abc import Generator
from pathlib import Path
from typing import Any

import pytest
from hypothesis import settings

# Property tests check behaviour, not speed: hypothesis's 200 ms a case failed a test of the
# chunk index under load (391 ms). The fuzz suites' own profile says the same.
settings.register_profile("suite", deadline=None)
settings.load_profile("suite")

# Nodes that tests start in this process give out and bind loopback (rosgraph's rules would
# otherwise give out this machine's name and listen on every interface).
os.environ.pop("ROS_HOSTNAME", None)
os.environ["ROS_IP"] = "127.0.0.1"
# The suite starts rostools as a child hundreds of times. Where the environment says not to
# write bytecode (some sandboxes do), every child compiled every module it imported, up to
# 0.7 s each: let the first child write it and the others read it.
os.environ.pop("PYTHONDONTWRITEBYTECODE", None)

#: In CI every peer is installed: a test that would skip (no corpus, no ROS 1, no shell, no
#: ``ip netns``) hides a broken feature in a green run, so it fails there, with its reason.
STRICT = os.environ.get("CI", "").lower() == "true"


#: xdist workers per CPU for ``-n auto`` (pyproject's addopts): most tests wait on peers and
#: sockets, not on the CPU. ``-n N`` or ``PYTEST_XDIST_AUTO_NUM_WORKERS`` choose otherwise.
WORKERS_PER_CPU = 3


def pytest_xdist_auto_num_workers(config: pytest.Config) -> int:
    """How many workers ``-n auto`` starts: none for tests named one by one (``FILE::TEST``),
    which would wait longer for the workers than for themselves."""
    if workers := os.environ.get("PYTEST_XDIST_AUTO_NUM_WORKERS"):
        return int(workers)
    if config.args and all("::" in arg for arg in config.args):
        return 0
    return WORKERS_PER_CPU * len(os.sched_getaffinity(0))


@pytest.hookimpl(tryfirst=True)
def pytest_configure(config: pytest.Config) -> None:
    """Measure the machine's load once per run, before any worker starts (they inherit it),
    and scale pytest-timeout's guard against a hung test by it (before pytest-timeout reads
    it; xdist's workers are handed the scaled value). Ctrl-C reaches the processes the tests
    start, however pytest was started."""
    from tests.support import load

    if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
        # started in the background of a script (``cmd &`` ignores Ctrl-C), every child would
        # ignore it too, and the tests of what Ctrl-C does would fail: a handler here is reset
        # to the default in each child at its start
        signal.signal(signal.SIGINT, signal.default_int_handler)
    factor = load.factor()
    if not hasattr(config, "workerinput") and getattr(config.option, "timeout", None):
        config.option.timeout *= factor


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(
    item: pytest.Item, call: pytest.CallInfo[None]
) -> Generator[None, Any, None]:
    """Under ``CI=true``, a skip is a failure that says why it would have skipped."""
    outcome = yield
    report = outcome.get_result()
    if STRICT and report.skipped and not hasattr(report, "wasxfail"):
        reason = report.longrepr[2] if isinstance(report.longrepr, tuple) else report.longrepr
        report.outcome = "failed"
        report.longrepr = f"CI=true, so no test may skip, and this one would have: {reason}"


@pytest.fixture
def cli_env(tmp_path: Path) -> dict[str, str]:
    """An environment for a rostools child: no inherited ROS settings, a private HOME."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS")}
    env["HOME"] = str(tmp_path / "home")
    env["ROS_MASTER_URI"] = "http://127.0.0.1:9"  # nothing listens on the discard port
    env["ROS_IP"] = "127.0.0.1"  # traffic stays on loopback
    env.pop("ROSTOOLS_MSG_PATH", None)
    env["ROS_PACKAGE_PATH"] = ""  # the built-in types only, whatever this machine has
    return env


@pytest.fixture
def rostools_master(cli_env: dict[str, str], tmp_path: Path):  # type: ignore[no-untyped-def]
    """``rostools core`` on a free port; ``cli_env`` points at it. Yields its URI."""
    from tests.support.procs import free_port, start_rostools_core

    port = free_port()
    cli_env["ROS_MASTER_URI"] = f"http://127.0.0.1:{port}"
    proc = start_rostools_core(port, cli_env)
    try:
        yield cli_env["ROS_MASTER_URI"]
    finally:
        proc.stop()


class MasterInfo:
    """A running master for a test: its kind, URI, and environments for peers."""

    def __init__(self, kind: str, uri: str, ros_env: dict[str, str], cli_env: dict[str, str]):
        self.kind = kind
        self.uri = uri
        self.ros_env = ros_env
        self.cli_env = cli_env


@pytest.fixture(params=["rostools", "roscore"])
def any_master(request, cli_env: dict[str, str], tmp_path: Path):  # type: ignore[no-untyped-def]
    """Each test runs twice: on ``rostools core`` and on a real ``roscore``."""
    from tests.support.env import ros1_missing
    from tests.support.procs import free_port, ros_env, start_roscore, start_rostools_core

    if request.param == "roscore" and (reason := ros1_missing()):
        pytest.skip(reason)
    port = free_port()
    uri = f"http://127.0.0.1:{port}"
    cli_env["ROS_MASTER_URI"] = uri
    env = ros_env(uri, tmp_path / "ros_home")
    # a test of what roslaunch does (rosout respawned) asks for roscore itself
    launch = request.node.get_closest_marker("roslaunch") is not None
    proc = (
        start_rostools_core(port, cli_env)
        if request.param == "rostools"
        else start_roscore(port, env, launch=launch)
    )
    try:
        yield MasterInfo(request.param, uri, env, cli_env)
    finally:
        proc.stop()
