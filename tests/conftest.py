"""Shared fixtures."""

from __future__ import annotations

import os
from pathlib import Path

import pytest


@pytest.fixture
def cli_env(tmp_path: Path) -> dict[str, str]:
    """An environment for a rostools child: no inherited ROS settings, a private HOME."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS")}
    env["HOME"] = str(tmp_path / "home")
    env["ROS_MASTER_URI"] = "http://127.0.0.1:9"  # nothing listens on the discard port
    env.pop("ROSTOOLS_MSG_PATH", None)
    env["ROS_PACKAGE_PATH"] = ""  # the built-in types only, whatever this machine has
    return env
