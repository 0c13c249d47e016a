"""Where ``rostools core`` listens and what it gives out, seen from other hosts."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import pytest

from tests.multihost.conftest import Site, start_master
from tests.support.env import SYSTEM_PYTHON, needs_ros1
from tests.support.netlab import Lab
from tests.support.procs import NODES, free_port

# one worker runs them all: one lab of namespaces and its masters (session fixtures), not one
# per worker
pytestmark = [pytest.mark.multihost, needs_ros1, pytest.mark.xdist_group("netns")]

#: Asks the master at argv[1] for its URI and /rosout's, as one JSON line.
LOOKUP = (
    "import json, sys, xmlrpc.client as x; p = x.ServerProxy(sys.argv[1]); "
    "print(json.dumps([p.getUri('/t')[2], p.lookupNode('/t', '/rosout')[2]]))"
)


def test_rosout_is_reached_and_remote_logs_arrive(site: Site) -> None:
    # the defect: 'core --host 0.0.0.0' gave out http://0.0.0.0:11311/ and its /rosout
    # registered at 0.0.0.0, so log messages from other hosts were lost
    lab, env = site.lab, site.env()
    asked = lab["hostb"].run([sys.executable, "-c", LOOKUP, site.uri], env)
    master, rosout = json.loads(asked.stdout)
    assert master == f"http://robot:{site.port}/"
    assert rosout.startswith("http://robot:")
    talker = lab["hostb"].start(
        [SYSTEM_PYTHON, str(NODES / "talker.py"), "/logged", "20", "0", "-1", "__name:=logger"], env
    )
    try:
        logs = lab["hostc"].rostools(
            "topic", "echo", "/rosout_agg", "-n", "1", "--filter", "m.name == '/logger'",
            "-F", "json", "--timeout", "20", env=env,
        )  # fmt: skip
        assert logs.returncode == 0, logs.stderr
        assert json.loads(logs.stdout)["msg"].startswith("said hello")
    finally:
        talker.stop()


def test_core_with_ros_ip_listens_and_is_reached(lab: Lab, tmp_path: Path) -> None:
    # the defect: with ROS_IP set to an address of the host, core exited 4 at once ("cannot
    # reach the master at http://127.0.0.1:11311/"): its /rosout called loopback, where
    # the master did not listen
    port = free_port()
    site = Site(lab, "rostools", port, tmp_path)
    robot = lab["robot"]
    env = site.env(ROS_IP=robot.address, ROS_MASTER_URI=f"http://{robot.address}:{port}")
    core = start_master(lab, "rostools", port, env)
    try:
        asked = lab["hostb"].run([sys.executable, "-c", LOOKUP, env["ROS_MASTER_URI"]], env)
        master, rosout = json.loads(asked.stdout)
        assert master == f"http://{robot.address}:{port}/"
        assert rosout.startswith(f"http://{robot.address}:")
        # on the robot itself, localhost reaches it too (it listens on every interface)
        local = site.env(ROS_MASTER_URI=f"http://localhost:{port}")
        assert "/rosout" in robot.rostools("node", "list", env=local).stdout
    finally:
        core.stop()


def test_a_bare_core_is_loopback_only_and_the_doctor_says_so(lab: Lab, tmp_path: Path) -> None:
    port = free_port()
    site = Site(lab, "rostools", port, tmp_path)
    core = start_master(lab, "rostools", port, site.env(ROS_MASTER_URI=f"http://localhost:{port}"))
    try:
        from_b = lab["hostb"].rostools(
            "doctor", env=site.env(ROS_MASTER_URI=f"http://robot:{port}")
        )
        assert from_b.returncode == 4
        assert (
            f"FAIL  master     cannot reach the master at http://robot:{port}: connection "
            "refused (hint: is a master running there, listening beyond loopback?"
        ) in from_b.stdout
    finally:
        core.stop()
