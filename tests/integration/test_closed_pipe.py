"""A reader that goes away (``| head -1``) ends every streaming command quietly, with exit 0.

rostopic, rosbag and rosparam end so when their reader closes the pipe; a script with
``set -o pipefail`` relies on it. Typer, as click, turned EPIPE into a silent exit 1.
"""

from __future__ import annotations

import os
import subprocess
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.support.bagdata import write_sample
from tests.support.env import CLI, needs_ros1, run_cli
from tests.support.procs import free_port, start_cli, start_rostools_core, wait_for

LIVE = [
    ["topic", "echo", "/chatter"],
    ["topic", "echo", "/chatter", "-p"],
    ["topic", "echo", "/chatter", "--format", "json"],
    ["topic", "hz", "/chatter"],
    ["topic", "bw", "/chatter"],
    ["topic", "list"],
    ["topic", "info", "/chatter"],
    ["param", "dump"],
    ["param", "get", "/"],
]
OFFLINE = [
    ["topic", "echo", "-b", "{bag}", "/chatter"],
    ["bag", "cat", "{bag}"],
    ["bag", "info", "{bag}"],
    ["msg", "proto", "std_msgs/Header"],
    ["msg", "show", "sensor_msgs/Image"],
]


def _closed_reader(argv: list[str], env: dict[str, str]) -> tuple[int, str]:
    """Run ``rostools ARGV`` with stdout a pipe whose reader has already gone."""
    read, write = os.pipe()
    os.close(read)
    proc = subprocess.Popen(
        [*CLI, *argv],
        stdout=write,
        stderr=subprocess.PIPE,
        env=env,
        start_new_session=True,
    )
    os.close(write)
    try:
        _, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, 9)
            proc.wait()
    return proc.returncode, err.decode(errors="replace")


@pytest.fixture(scope="module")
def talking(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, str]]:
    """A master with a /chatter publisher at 50 Hz; the environment to reach it."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS")}
    env["HOME"] = str(tmp_path_factory.mktemp("home"))
    env["ROS_IP"] = "127.0.0.1"
    port = free_port()
    env["ROS_MASTER_URI"] = f"http://127.0.0.1:{port}"
    core = start_rostools_core(port, env)
    pub = start_cli("topic", "pub", "/chatter", "std_msgs/String", "hello", "-r", "50", env=env)
    try:
        wait_for(lambda: "/chatter" in run_cli("topic", "list", env=env).stdout, 15, "/chatter")
        yield env
    finally:
        pub.stop()
        core.stop()


@pytest.mark.parametrize("argv", LIVE, ids=" ".join)
def test_a_live_command_ends_quietly(talking: dict[str, str], argv: list[str]) -> None:
    code, err = _closed_reader(argv, talking)
    assert code == 0, err
    assert "Traceback" not in err and "rostools:" not in err, err


@pytest.mark.parametrize("argv", OFFLINE, ids=" ".join)
def test_an_offline_command_ends_quietly(
    tmp_path: Path, cli_env: dict[str, str], argv: list[str]
) -> None:
    bag = write_sample(tmp_path / "s.bag", 400).path
    code, err = _closed_reader([a.format(bag=bag) for a in argv], cli_env)
    assert code == 0, err
    assert err == "", err


@pytest.mark.interop
@needs_ros1
@pytest.mark.parametrize("argv", [["echo", "/chatter"], ["echo", "-p", "/chatter"]], ids=" ".join)
def test_rostopic_ends_the_same(talking: dict[str, str], argv: list[str]) -> None:
    read, write = os.pipe()
    os.close(read)
    theirs = subprocess.run(["rostopic", *argv], stdout=write, stderr=subprocess.PIPE,
                            env=talking, timeout=60, check=False)  # fmt: skip
    os.close(write)
    ours, err = _closed_reader(["topic", *argv], talking)
    assert (ours, theirs.returncode) == (0, 0), (err, theirs.stderr)
