"""``param ... -v`` and ``get -p`` print what rosparam prints, on stdout, line for line.

The -v lines had moved to stderr with other wording: ``dump -v`` lost its ``name=value``
lines and ``load -v`` read differently. ``get -p`` ended with a blank line rosparam omits.
"""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

from tests.support.env import needs_ros1, run_cli

pytestmark = [pytest.mark.interop, needs_ros1]

DOCS = "a: 1\nb: {c: x, d: [1, 2.5]}\n---\n_ns: sub\ne: true\n"


def _rosparam(env: dict[str, str], cwd: Path, *argv: str) -> str:
    done = subprocess.run(["rosparam", *argv], env=dict(env, ROS_HOME=str(cwd)), cwd=cwd,
                          capture_output=True, text=True, timeout=60, check=False)  # fmt: skip
    assert done.returncode == 0, done.stderr
    return done.stdout


def _ours(env: dict[str, str], cwd: Path, *argv: str) -> str:
    done = run_cli("param", *argv, env=env, cwd=cwd)
    assert (done.returncode, done.stderr) == (0, ""), done.stderr
    return done.stdout


@pytest.mark.parametrize(
    "steps",
    [
        [["set", "-v", "{p}", "{{x: 1, y: [1, 2], z: {{w: true, t: text}}}}"],
         ["get", "-v", "{p}"], ["get", "-p", "{p}/z"], ["get", "-p", "{p}/z/t"],
         ["set", "{p}/m", "'a: b\\nc'"], ["get", "-p", "{p}/m"],
         ["get", "-p", "{p}/x"], ["set", "{p}/u", "{{unicode: héllo}}"], ["get", "-p", "{p}/u"],
         ["dump", "-v", "{f}", "{p}"], ["delete", "-v", "{p}/z"]],
        [["load", "-v", "{docs}", "{p}"], ["get", "{p}"], ["delete", "-v", "{p}"]],
    ],
    ids=["set-get-dump-delete", "load"],
)  # fmt: skip
def test_verbose_and_pretty_print_as_rosparam(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path, steps: list[list[str]]
) -> None:
    docs = tmp_path / "docs.yaml"
    docs.write_text(DOCS)
    for step in steps:  # each tool in a namespace of its own
        mine = _ours(
            cli_env, tmp_path, *(a.format(p="/ours", f="ours.yaml", docs=docs) for a in step)
        )
        theirs = _rosparam(
            cli_env, tmp_path, *(a.format(p="/theirs", f="theirs.yaml", docs=docs) for a in step)
        )
        assert mine == theirs.replace("/theirs", "/ours").replace("theirs.yaml", "ours.yaml"), step
    if (tmp_path / "theirs.yaml").exists():
        assert (tmp_path / "ours.yaml").read_text() == (tmp_path / "theirs.yaml").read_text()
