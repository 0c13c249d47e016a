"""Helpers for tests: running the CLI as a user would, and finding the real ROS 1 peers."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.support.load import scaled
from tests.support.reap import run

ROOT = Path(__file__).resolve().parent.parent.parent
# Third-party bags live beside the project (../shared/corpus); ROSTOOLS_CORPUS overrides.
CORPUS = Path(os.environ.get("ROSTOOLS_CORPUS", ROOT.parent / "shared" / "corpus"))
needs_corpus = pytest.mark.skipif(
    not (CORPUS / "MANIFEST.tsv").is_file(), reason=f"the shared corpus is not at {CORPUS}"
)
SYSTEM_PYTHON = "/usr/bin/python3"
#: The command line of rostools as a user runs it, for ``run_cli`` and ``procs.start_cli``.
CLI = [sys.executable, "-m", "rostools"]


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
    *args: str,
    env: dict[str, str] | None = None,
    input: str | None = None,
    timeout: float = 60,
    cwd: Path | None = None,
) -> subprocess.CompletedProcess[str]:
    """Run ``python -m rostools ARGS`` (in ``cwd``) and capture its output; ``timeout`` is
    scaled by the run's load factor."""
    return run([*CLI, *args], env=env, cwd=cwd, input=input, timeout=scaled(timeout))


def run_system_python(code: str, *args: str, input: str | None = None, timeout: float = 300) -> str:
    """Run Python code on the system interpreter (the one the real ROS 1 lives on)."""
    proc = run([SYSTEM_PYTHON, "-c", code, *args], input=input, timeout=timeout)
    if proc.returncode != 0:
        raise AssertionError(f"system python failed:\n{proc.stderr[-3000:]}")
    return proc.stdout


def ask_ros1(requests: list[dict[str, object]]) -> list[object]:
    """Send requests to ``ros1_oracle.py`` on the system python; its answers, in order.

    A request the reference stack fails on answers an ``{"error": ...}`` dict, so a test can
    tell an unsupported type from a mismatch.
    """
    import json

    oracle = Path(__file__).with_name("ros1_oracle.py")
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS")}
    proc = run(
        [SYSTEM_PYTHON, str(oracle)],
        input="".join(json.dumps(r) + "\n" for r in requests),
        env=env,
        timeout=600,
    )
    if proc.returncode != 0:
        raise AssertionError(f"ros1_oracle failed:\n{proc.stderr[-3000:]}")
    answers = [json.loads(line) for line in proc.stdout.splitlines()]
    assert len(answers) == len(requests)
    return [a.get("ok", a) for a in answers]
