"""Under ``CI=true`` a test that would skip fails and says why (tests/conftest.py)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent.parent


def _doctor_tests(tmp_path: Path, ci: str) -> subprocess.CompletedProcess[str]:
    env = dict(os.environ, CI=ci, ROSTOOLS_CORPUS=str(tmp_path / "moved-away"))
    return subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-n", "0",
         "-k", "cli_lines", "tests/corpus/test_bag_doctor.py"],
        cwd=ROOT, env=env, capture_output=True, text=True, timeout=120, check=False,
    )  # fmt: skip


def test_the_corpus_moved_away_fails_ci_and_says_why(tmp_path: Path) -> None:
    done = _doctor_tests(tmp_path, "true")
    assert done.returncode == 1, done.stdout
    assert "CI=true, so no test may skip, and this one would have: Skipped: the shared corpus" in (
        done.stdout
    )


def test_elsewhere_it_skips_with_the_reason(tmp_path: Path) -> None:
    done = _doctor_tests(tmp_path, "")
    assert done.returncode == 0, done.stdout
    assert "1 skipped" in done.stdout


def test_ci_runs_strict() -> None:
    """``.ci/run`` sets ``CI=true`` before the test command of docs/development.md."""
    lines = (ROOT / ".ci" / "run").read_text().splitlines()
    strict = lines.index("export CI=true")
    assert any(line.endswith("&& pytest") for line in lines[strict + 1 :]), lines
