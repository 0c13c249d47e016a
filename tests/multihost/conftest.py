"""Hosts in network namespaces, with a master on ``robot``: rostools core or a real roscore.

The hosts, on 10.223.0.0/24 (inside the namespaces only):
- ``robot`` (.1), ``hostb`` (.2), ``hostc`` (.3): every host's ``/etc/hosts`` names them;
- ``hostd`` (.4): as Debian installs it, its own ``/etc/hosts`` maps its name to 127.0.1.1,
  and no other host knows the name;
- ``hoste`` (.5): nobody knows its name, itself included.

No host sets ``ROS_IP`` or ``ROS_HOSTNAME`` unless a test says so: the default rules are
what these tests are about.
"""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.support import netlab
from tests.support.env import ros1_missing
from tests.support.netlab import Lab
from tests.support.procs import Proc, free_port

GOOD = ("robot", "hostb", "hostc")
HOSTS = (*GOOD, "hostd", "hoste")


@pytest.fixture(scope="session")
def lab() -> Iterator[Lab]:
    """The five hosts, for the whole session; deleted at its end, pass or fail."""
    if reason := netlab.missing():
        pytest.skip(reason)
    with Lab(HOSTS) as made:
        known = {name: made[name].address for name in GOOD}
        for name in GOOD:
            made[name].set_hosts(known)
        made["hostd"].set_hosts({**known, "hostd": "127.0.1.1"})
        made["hoste"].set_hosts(known)
        yield made


class Site:
    """A master running on ``robot`` and the environments to reach it from any host."""

    def __init__(self, lab: Lab, kind: str, port: int, home: Path) -> None:
        self.lab = lab
        self.kind = kind
        self.port = port
        self.home = home
        self.uri = f"http://robot:{port}"

    def env(self, **extra: str) -> dict[str, str]:
        """A clean environment for any process on any host (``ROS_MASTER_URI`` = robot's)."""
        env = {k: v for k, v in os.environ.items() if not k.startswith("ROS")}
        env.update(
            ROS_MASTER_URI=self.uri,
            ROS_HOME=str(self.home),
            ROS_LOG_DIR=str(self.home / "log"),
            ROS_PACKAGE_PATH="",
            PYTHONUNBUFFERED="1",
        )
        env.update(extra)
        return env


def start_master(lab: Lab, kind: str, port: int, env: dict[str, str], *args: str) -> Proc:
    """rostools core (listening beyond loopback) or roscore on ``robot``, once it answers."""
    argv = (
        [sys.executable, "-m", "rostools", "core", "--port", str(port), *args]
        if kind == "rostools"
        else ["roscore", "-p", str(port), *args]
    )
    proc = lab["robot"].start(argv, env)
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline and proc.popen.poll() is None:
        if lab["robot"].rostools("param", "get", "/rosdistro", env=env).returncode == 0:
            return proc
        time.sleep(0.2)
    proc.stop()
    raise AssertionError(f"{kind} did not start on robot: {proc.output()[1][-2000:]}")


@pytest.fixture(scope="session", params=["rostools", "roscore"])
def site(
    request: pytest.FixtureRequest, lab: Lab, tmp_path_factory: pytest.TempPathFactory
) -> Iterator[Site]:
    """A master on ``robot`` for the session's multi-host tests, once per kind."""
    if request.param == "roscore" and (reason := ros1_missing()):
        pytest.skip(reason)
    made = Site(lab, request.param, free_port(), tmp_path_factory.mktemp("site"))
    # a bare 'rostools core' listens on loopback only; on a robot it is told otherwise
    extra = ("--host", "0.0.0.0") if request.param == "rostools" else ()
    proc = start_master(lab, request.param, made.port, made.env(), *extra)
    try:
        yield made
    finally:
        proc.stop()
