"""``rostools demo``: the first five minutes, on a machine without ROS."""

from __future__ import annotations

import re
import socket
import threading
import time
from pathlib import Path

import pytest

from rostools.bag.formats.access import bag_info
from tests.support.env import run_cli
from tests.support.procs import wait_for


def test_demo_runs_the_main_job_and_leaves_nothing_running(
    cli_env: dict[str, str], tmp_path: Path
) -> None:
    env = {k: v for k, v in cli_env.items() if k != "ROS_MASTER_URI"}
    started = time.monotonic()
    done = run_cli("demo", env=env, cwd=tmp_path, timeout=60)
    took = time.monotonic() - started
    assert done.returncode == 0, done.stdout + done.stderr
    # about 8 s here; the bound tells a wait that never ends from a loaded machine
    assert took < 30, took
    out = done.stdout
    for shown in (
        "$ rostools topic list\n/chatter",
        'data: "hello world',
        "average rate: ",
        "sum: 5",
        "robot_name: demo_bot",
        "$ rostools bag info demo.mcap",
    ):
        assert shown in out, shown
    info = bag_info(tmp_path / "demo.mcap")
    assert 20 <= info.message_count <= 35  # three seconds at 10 Hz
    recorded = re.search(r"recorded (\d+) messages", out)
    assert recorded and int(recorded.group(1)) == info.message_count
    port = int(re.search(r"a master at http://[^:]+:(\d+)/", out).group(1))  # type: ignore[union-attr]
    with socket.socket() as probe:  # nothing is left listening
        assert probe.connect_ex(("127.0.0.1", port)) != 0


def test_demo_in_a_read_only_folder_records_in_a_temporary_one(cli_env: dict[str, str]) -> None:
    # the defect: the recording step failed; /proc refuses a new file even to root
    env = {k: v for k, v in cli_env.items() if k != "ROS_MASTER_URI"}
    done = run_cli("demo", env=env, cwd=Path("/proc"), timeout=60)
    assert done.returncode == 0, done.stdout + done.stderr
    found = re.search(r"this folder is read-only: recording to (\S+demo\.mcap)\)", done.stdout)
    assert found, done.stdout
    recorded = Path(found.group(1))
    try:
        assert bag_info(recorded).message_count >= 20
    finally:
        recorded.unlink()
        recorded.parent.rmdir()
    given = run_cli("demo", "-O", "/proc/x.mcap", env=env, timeout=60)
    assert given.returncode == 2
    assert given.stderr.startswith("rostools: cannot write /proc/x.mcap: /proc: "), given.stderr


def test_a_second_run_keeps_the_first_recording(cli_env: dict[str, str], tmp_path: Path) -> None:
    # the defect: a second run wrote over demo.mcap without a word
    env = {k: v for k, v in cli_env.items() if k != "ROS_MASTER_URI"}
    (tmp_path / "demo.mcap").write_bytes(b"the first run's recording")
    done = run_cli("demo", env=env, cwd=tmp_path, timeout=60)
    assert done.returncode == 0, done.stdout + done.stderr
    assert (tmp_path / "demo.mcap").read_bytes() == b"the first run's recording"
    assert done.stdout.startswith("(demo.mcap is here already: recording to demo-2.mcap)\n")
    assert "$ rostools bag info demo-2.mcap" in done.stdout
    assert "and demo-2.mcap is yours" in done.stdout
    assert bag_info(tmp_path / "demo-2.mcap").message_count >= 20


def test_the_demos_nodes_say_nothing_false_of_their_own_master(
    capfd: pytest.CaptureFixture[str],
) -> None:
    # the defect: on a loaded machine the in-process master answered the nodes' watch late,
    # and they printed that it did not answer, then that it was back; it runs beside them
    from rostools.cli.demo import DemoGraph
    from rostools.master.server import MasterThread

    with MasterThread() as master, DemoGraph(master.uri) as graph:
        talker = graph.nodes[0]
        assert master.loop is not None
        answering = threading.Event()
        master.loop.call_soon_threadsafe(answering.wait)  # the master answers nothing now ...
        try:
            wait_for(lambda: talker.master_lost, 30, "the talker's watch to miss the master")
        finally:
            answering.set()  # ... and then again
        wait_for(lambda: not talker.master_lost, 30, "the talker's watch to find it back")
    assert "master" not in capfd.readouterr().err
