"""Helpers for tests: running the CLI as a user would, and finding the real ROS 1 peers."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent.parent
CORPUS = ROOT.parent / "shared" / "corpus"
SYSTEM_PYTHON = "/usr/bin/python3"


def ros1_missing() -> str | None:
    """Why the real ROS 1 peers cannot be used here, or None when they can."""
    if not shutil.which("rosmsg") or not Path(SYSTEM_PYTHON).exists():
        return "real ROS 1 not installed (run scripts/install-ros1-peers.sh)"
    probe = subprocess.run(
        [SYSTEM_PYTHON, "-c", "import genpy, genmsg, rosmsg, rostopic"],
        capture_output=True,
        check=False,
    )
    if probe.returncode != 0:
        return "the system python cannot import genpy/rosmsg (install-ros1-peers.sh)"
    return None


_ROS1_REASON = ros1_missing()
needs_ros1 = pytest.mark.skipif(_ROS1_REASON is not None, reason=_ROS1_REASON or "")


def run_cli(
    *args: str, env: dict[str, str] | None = None, input: str | None = None, timeout: float = 60
) -> subprocess.CompletedProcess[str]:
    """Run ``python -m rostools ARGS`` and capture its output."""
    return subprocess.run(
        [sys.executable, "-m", "rostools", *args],
        capture_output=True,
        text=True,
        env=env,
        input=input,
        timeout=timeout,
        check=False,
    )


def run_system_python(code: str, *args: str, input: str | None = None, timeout: float = 300) -> str:
    """Run Python code on the system interpreter (the one the real ROS 1 lives on)."""
    proc = subprocess.run(
        [SYSTEM_PYTHON, "-c", code, *args],
        capture_output=True,
        text=True,
        input=input,
        timeout=timeout,
        check=False,
    )
    if proc.returncode != 0:
        raise AssertionError(f"system python failed:\n{proc.stderr[-3000:]}")
    return proc.stdout
