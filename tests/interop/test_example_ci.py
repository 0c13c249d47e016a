"""``examples/ci``: docs/testing.md's robot package, its pytest suite run as a user's CI runs it.

Real rospy nodes under the plugin's per-test masters; the suite's own pytest, in a child.
"""

from __future__ import annotations

import os
import subprocess
import sys

import pytest

from tests.support.env import ROOT, SYSTEM_PYTHON, needs_ros1

pytestmark = [pytest.mark.interop, needs_ros1]


def test_the_example_suite_passes_against_rospy_nodes() -> None:
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS")}
    env.update(ROS_PYTHON=SYSTEM_PYTHON, PYTHONDONTWRITEBYTECODE="1")
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-rA"],
        cwd=ROOT / "examples" / "ci",
        env=env,
        capture_output=True,
        text=True,
        timeout=120,
        check=False,
    )
    assert done.returncode == 0, done.stdout[-4000:] + done.stderr[-2000:]
    assert "3 passed" in done.stdout, done.stdout[-2000:]
