"""tf2's own ``BufferCore`` on the system python (``tf2_oracle.py``), and the mark that skips
a test where it is missing."""

from __future__ import annotations

import json
import os
import subprocess
from pathlib import Path
from typing import Any

import pytest

from tests.support.env import SYSTEM_PYTHON
from tests.support.reap import run


def tf2_missing() -> str | None:
    """Why tf2_py and rosbag cannot be used from the system python, or None."""
    if not Path(SYSTEM_PYTHON).exists():
        return "no system python"
    probe = subprocess.run(
        [SYSTEM_PYTHON, "-c", "import tf2_py, rosbag, tf2_ros"], capture_output=True, check=False
    )
    if probe.returncode != 0:
        return "tf2_py/tf2_ros not installed (run scripts/install-ros1-peers.sh)"
    return None


_REASON = tf2_missing()
needs_tf2 = pytest.mark.skipif(_REASON is not None, reason=_REASON or "")


def ask_tf2(cache_ns: int, ops: list[list[Any]]) -> list[dict[str, Any]]:
    """tf2's answers to ``ops`` (see ``tf2_oracle.py``), one per lookup or yaml."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS_")}
    proc = run(
        [SYSTEM_PYTHON, str(Path(__file__).with_name("tf2_oracle.py"))],
        input=json.dumps({"cache_ns": cache_ns, "ops": ops}),
        env=env,
        timeout=600,
    )
    if proc.returncode != 0:
        raise AssertionError(f"tf2_oracle failed:\n{proc.stderr[-3000:]}")
    answers: list[dict[str, Any]] = json.loads(proc.stdout)
    return answers
