"""A slow master never costs a topic, and never makes a command overrun its ``--timeout``.

Each test puts a proxy (``tests/support/slowmaster.py``) between our commands and a master,
ours or a real ``roscore``, that holds back the calls of one method past
``ROSTOOLS_MASTER_TIMEOUT``; the master still carries each one out, as a busy rosmaster does.
The publishers are real rospy talkers. rosbag record waits for such a master, and records.
"""

from __future__ import annotations

import json
import signal
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from rostools.bag.formats.access import open_bag
from tests.conftest import MasterInfo
from tests.support.bagdata import recorded
from tests.support.env import run_cli
from tests.support.procs import (
    Proc,
    linked,
    publishers,
    start_cli,
    start_ros1_node,
    subscribers,
    wait_for,
)
from tests.support.slowmaster import SlowMaster, slow_master

pytestmark = pytest.mark.interop

#: Our commands' limit on a master call here, and how long the proxy holds a slow one back.
LIMIT, SLOW = 1.0, 2.5


@pytest.fixture
def slow(any_master: MasterInfo) -> Iterator[tuple[SlowMaster, dict[str, str]]]:
    """The proxy in front of the master, and an environment for rostools on the proxy."""
    with slow_master(any_master.uri) as proxy:
        env = dict(any_master.cli_env)
        env["ROS_MASTER_URI"] = proxy.uri
        env["ROSTOOLS_MASTER_TIMEOUT"] = str(LIMIT)
        yield proxy, env


@pytest.fixture
def procs() -> Iterator[list[Proc]]:
    """Processes the test starts, stopped after it by PID."""
    started: list[Proc] = []
    yield started
    for proc in reversed(started):
        proc.stop()


def talker(any_master: MasterInfo, topic: str, procs: list[Proc]) -> None:
    """A rospy talker on ``topic`` (20 Hz), once the master lists it."""
    name = "__name:=talker" + topic.replace("/", "_")
    procs.append(start_ros1_node("talker.py", [topic, "20", "0", "-1", name], any_master.ros_env))
    wait_for(lambda: publishers(any_master.uri, topic), 30, f"a publisher of {topic}")


def retry_lines(err: str, topic: str = "") -> list[str]:
    """The lines that say a subscription (to ``topic``) is being registered again."""
    said = f"did not answer registerSubscriber within {LIMIT:g} s; registering subscription {topic}"
    return [line for line in err.splitlines() if said in line]


def test_a_topic_the_master_is_slow_to_register_mid_recording_is_recorded(
    any_master: MasterInfo,
    slow: tuple[SlowMaster, dict[str, str]],
    procs: list[Proc],
    tmp_path: Path,
) -> None:
    # The recorder gave up on the one registration it timed out, silently, and exited 0
    # without a message of /later, where rosbag record waits and records.
    proxy, env = slow
    talker(any_master, "/early", procs)
    record = start_cli("bag", "record", "-a", "-O", str(tmp_path / "run.bag"), env=env)
    procs.append(record)
    active = tmp_path / "run.bag.active"
    wait_for(lambda: recorded(active, "/early") >= 3, 30, "/early recorded", 0.2)
    proxy.delay("registerSubscriber", SLOW, only="/later")
    talker(any_master, "/later", procs)
    wait_for(lambda: recorded(active, "/later") >= 5, 60, "/later recorded", 0.2)
    record.signal(signal.SIGINT)
    assert record.popen.wait(30) == 0
    _, err = record.output()
    assert proxy.delayed["registerSubscriber"] >= 1
    assert len(retry_lines(err, "/later")) == 1, err
    assert "has taken 1 registration(s) it was slow to answer" in err
    assert "restarted" not in err  # the watch did not take the wait for a new master
    with open_bag(tmp_path / "run.bag") as reader:
        later = [bytes(d[4:]).decode() for _, _, d in reader.messages(["/later"])]
    assert len(later) >= 5 and all(text.startswith("hello") for text in later)


@pytest.mark.parametrize("out", ["run.bag", "run.mcap"])
def test_a_recorder_started_on_a_slow_master_records(
    out: str,
    any_master: MasterInfo,
    slow: tuple[SlowMaster, dict[str, str]],
    procs: list[Proc],
    tmp_path: Path,
) -> None:
    # At start-up the first slow registration ended the recorder: exit 5, nothing recorded.
    proxy, env = slow
    talker(any_master, "/chatter", procs)
    proxy.delay("registerSubscriber", SLOW)
    record = start_cli("bag", "record", "-a", "-O", str(tmp_path / out), env=env)
    procs.append(record)
    active = tmp_path / f"{out}.active"
    wait_for(lambda: recorded(active, "/chatter") >= 5, 60, "/chatter recorded", 0.2)
    record.signal(signal.SIGINT)
    assert record.popen.wait(30) == 0
    _, err = record.output()
    assert proxy.delayed["registerSubscriber"] >= 1
    assert len(retry_lines(err)) == 1, err  # one line for the episode, not one per topic
    assert "restarted" not in err
    assert recorded(tmp_path / out, "/chatter") >= 5


def test_a_snapshot_started_on_a_slow_master_follows_its_topics(
    any_master: MasterInfo,
    slow: tuple[SlowMaster, dict[str, str]],
    procs: list[Proc],
    tmp_path: Path,
) -> None:
    proxy, env = slow
    talker(any_master, "/chatter", procs)
    proxy.delay("registerSubscriber", SLOW)
    snap = start_cli("bag", "snapshot", "-a", "-o", str(tmp_path / "s"), "__name:=snap", env=env)
    procs.append(snap)
    wait_for(lambda: "/snap" in subscribers(any_master.uri, "/chatter"), 60, "snap subscribed")
    wait_for(lambda: linked(any_master.uri, "/snap", "/chatter"), 60, "snap connected")
    snap.signal(signal.SIGINT)
    _, err = snap.output()
    assert snap.popen.returncode == 0, err
    assert proxy.delayed["registerSubscriber"] >= 1


def test_echo_started_on_a_slow_master_prints(
    any_master: MasterInfo, slow: tuple[SlowMaster, dict[str, str]], procs: list[Proc]
) -> None:
    proxy, env = slow
    talker(any_master, "/chatter", procs)
    proxy.delay("registerSubscriber", SLOW)
    done = run_cli("topic", "echo", "/chatter", "-n", "3", "-F", "json", env=env, timeout=60)
    assert done.returncode == 0, done.stderr
    lines = [json.loads(line) for line in done.stdout.splitlines()]
    assert [m["data"][:5] for m in lines if "event" not in m] == ["hello"] * 3
    # with --format json the notices join the stream too
    events = [m["event"] for m in lines if "event" in m]
    assert events == ["register_retry", "registered"], lines
    assert len(retry_lines(done.stderr, "/chatter")) == 1, done.stderr
    assert proxy.delayed["registerSubscriber"] >= 1


@pytest.mark.parametrize(
    ("args", "method", "said"),
    [
        (["topic", "echo", "/x"], "getTopicTypes", "/x did not deliver a message within 1 s"),
        (["topic", "hz", "/x"], "getTopicTypes", "no message on /x within 1 s"),
        (
            ["service", "call", "--wait", "/s"],
            "getSystemState",
            "service /s did not appear within 1 s",
        ),
        (["bag", "trigger"], "hasParam", "the snapshot was not complete within 1"),
    ],
    ids=["echo", "hz", "service call --wait", "bag trigger"],
)
def test_a_slow_master_does_not_make_a_command_overrun_its_timeout(
    args: list[str],
    method: str,
    said: str,
    any_master: MasterInfo,
    slow: tuple[SlowMaster, dict[str, str]],
) -> None:
    # Each poll of the master took the master's whole limit, whatever was left of --timeout:
    # the command said the master did not answer, long after its own limit.
    proxy, env = slow
    env["ROSTOOLS_MASTER_TIMEOUT"] = "60"
    proxy.delay(method, 90)
    started = time.monotonic()
    done = run_cli(*args, "--timeout", "1", env=env, timeout=50)
    assert done.returncode == 5, done.stderr
    assert done.stderr.strip().splitlines()[-1] == f"rostools: {said}"
    assert proxy.delayed[method] >= 1
    assert time.monotonic() - started < 50  # well before the master's own 60 s


def test_echo_of_a_bag_refuses_a_timeout(tmp_path: Path, cli_env: dict[str, str]) -> None:
    # --timeout was ignored with -b; a bag is read to its end.
    done = run_cli(
        "topic", "echo", "-b", str(tmp_path / "x.bag"), "/t", "--timeout", "1", env=cli_env
    )
    assert done.returncode == 2
    assert done.stderr.strip() == (
        "rostools: --timeout does not apply to a bag (-b): it is read to its end"
    )
