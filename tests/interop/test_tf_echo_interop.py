"""``rostools tf echo`` live beside the real tools: ``static_transform_publisher`` and a rospy
``TransformBroadcaster`` of a moving frame, on ``rostools core`` and on a real ``roscore``.

The same times give the same transforms as tf2's ``echo.py -t TIME -p 12`` to 1e-9, and the
argument order is ``tf_echo``'s (``tf echo A B``: B's pose in A).
"""

from __future__ import annotations

import json
import re
import time
from collections.abc import Iterator

import pytest

from tests.conftest import MasterInfo
from tests.support.env import run_cli
from tests.support.load import scaled
from tests.support.procs import Proc, publishers, start_ros1_node, wait_for
from tests.support.tf2peer import needs_tf2

pytestmark = needs_tf2

GRID = 15_625_000  # the broadcaster's stamps: every 1/64 s
NUMBERS = re.compile(r"\[([^\]]*)\]")


@pytest.fixture
def tf_graph(any_master: MasterInfo) -> Iterator[MasterInfo]:
    """base -> cam static (x y z yaw pitch roll), odom -> base moving."""
    env = any_master.ros_env
    pose = ["1", "2", "3", "0.1", "0.2", "0.3", "base", "cam"]
    static = Proc(["/usr/lib/tf2_ros/static_transform_publisher", *pose], env=env)
    moving = start_ros1_node("tf_broadcaster.py", ["odom", "base"], env)
    try:
        yield any_master
    finally:
        moving.stop()
        static.stop()


def _ours(master: MasterInfo, *args: str) -> list[dict[str, object]]:
    proc = run_cli("tf", "echo", *args, "-F", "json", env=master.cli_env, timeout=90)
    assert proc.returncode == 0, proc.stderr
    return [json.loads(line) for line in proc.stdout.splitlines()]


def _blocks(text: str) -> list[list[float]]:
    """The numbers of each printed answer (translation, quaternion, RPY, degrees)."""
    out: list[list[float]] = []
    for block in text.split("At time")[1:]:
        rows = NUMBERS.findall(block)[:4]
        out.append([float(v) for row in rows for v in row.split(",")])
    return out


def test_the_same_times_give_the_same_transforms_as_tf2s_echo(tf_graph: MasterInfo) -> None:
    first = _ours(tf_graph, "odom", "cam", "-n", "1", "--timeout", "60")[0]
    # a time a little ahead, between two of the broadcaster's stamps: both tools wait for it
    ahead = int(first["stamp_ns"]) + 3_000_000_000  # type: ignore[call-overload]
    at_ns = ahead // GRID * GRID + GRID // 2
    at = f"{at_ns // 1_000_000_000}.{at_ns % 1_000_000_000:09d}"
    flags = ["-t", at, "-p", "12", "-r", "2", "-l", "40"]
    peer = Proc(
        ["/usr/bin/python3", "/usr/lib/tf2_tools/echo.py", "odom", "cam", *flags],
        env=tf_graph.ros_env,
    )
    try:
        ours = _ours(tf_graph, "odom", "cam", "--at", at, "-n", "1", "--timeout", "60")[0]
        peer.expect(r"in RPY \(degree\)", timeout=60)
    finally:
        peer.stop()
    theirs = _blocks("".join(peer.seen))[0]
    assert ours["stamp_ns"] == at_ns
    mine = [*ours["translation"], *ours["rotation"], *ours["rpy"]]  # type: ignore[misc]
    assert mine == pytest.approx(theirs[:10], abs=1e-9)
    assert ours["rpy_degrees"] == pytest.approx(theirs[10:], abs=1e-9)


def _tf_echo(master: MasterInfo, a: str, b: str) -> list[float]:
    peer = Proc(["/usr/lib/tf/tf_echo", a, b], env=master.ros_env)
    try:
        peer.expect(r"in RPY \(degree\)", timeout=60)
    finally:
        peer.stop()
    return _blocks("".join(peer.seen))[0]


@pytest.mark.parametrize(("a", "b"), [("base", "cam"), ("cam", "base")])
def test_the_argument_order_is_tf_echos(tf_graph: MasterInfo, a: str, b: str) -> None:
    theirs = _tf_echo(tf_graph, a, b)  # tf_echo prints 3 decimals
    ours = _ours(tf_graph, a, b, "-n", "1", "--timeout", "60")[0]
    mine = [*ours["translation"], *ours["rotation"]]  # type: ignore[misc]
    assert mine == pytest.approx(theirs[:7], abs=0.0015)
    if (a, b) == ("base", "cam"):  # cam's pose in base: the publisher's own numbers
        assert ours["translation"] == pytest.approx([1.0, 2.0, 3.0])


def test_it_prints_at_its_rate_and_stops_at_its_count(tf_graph: MasterInfo) -> None:
    started = time.monotonic()
    answers = _ours(tf_graph, "odom", "cam", "-r", "10", "-n", "5", "--timeout", "60")
    assert len(answers) == 5
    stamps = [a["stamp_ns"] for a in answers]
    assert stamps == sorted(stamps) and len(set(stamps)) > 1  # the frame moves on
    assert time.monotonic() - started > 0.4  # four periods of 0.1 s at least


def _complete(master: MasterInfo, deadline: float, *words: str) -> list[str]:
    env = {**master.cli_env, "ROSTOOLS_COMPLETE_DEADLINE": str(deadline)}
    argv = ["rostools", "tf", "echo", *words]
    proc = run_cli("__complete", "bash", str(len(argv) - 1), *argv, env=env)
    assert proc.returncode == 0, proc.stderr
    return [line.split("\t")[0] for line in proc.stdout.splitlines()]


def test_frame_names_complete_from_the_live_tf_topics(tf_graph: MasterInfo) -> None:
    # generous: a loaded machine is slow to connect, and a deadline only bounds the wait
    wait_for(lambda: _complete(tf_graph, 5, "") == ["base", "cam", "odom"], 60, "frames")
    assert _complete(tf_graph, 5, "odom", "c") == ["cam"]


def test_a_silent_tf_publisher_costs_completion_its_deadline_only(tf_graph: MasterInfo) -> None:
    silent = start_ros1_node("tf_broadcaster.py", ["odom", "base", "silent"], tf_graph.ros_env)
    try:
        wait_for(lambda: "/silent_broadcaster" in publishers(tf_graph.uri, "/tf"), 60, "silent")
        started = time.monotonic()
        frames = _complete(tf_graph, 1, "")
        # the interpreter's start-up is not under the deadline: a loaded machine's slack
        assert time.monotonic() - started < scaled(20)
        assert set(frames) <= {"base", "cam", "odom"}
    finally:
        silent.stop()


def test_bad_input_is_one_line(tf_graph: MasterInfo) -> None:
    env = tf_graph.cli_env
    missing = run_cli("tf", "echo", "odom", "nowhere", "--timeout", "3", env=env)
    assert missing.returncode == 5
    assert "does not exist" in missing.stderr and len(missing.stderr.splitlines()) == 1
    empty = run_cli("tf", "echo", "/", "cam", env=env)
    assert empty.returncode == 2 and len(empty.stderr.splitlines()) == 1
    at = run_cli("tf", "echo", "odom", "cam", "--at", "soon", env=env)
    assert at.returncode == 2 and "--at" in at.stderr
