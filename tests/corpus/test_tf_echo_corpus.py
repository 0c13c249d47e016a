"""``tf echo -b`` over the corpus bags that hold ``/tf``: the same answers as tf2's own
``BufferCore`` fed from the same bag by the ``rosbag`` module, at 100 sampled times each."""

from __future__ import annotations

import json
import random
from pathlib import Path
from typing import Any

import pytest

from rostools.bag.formats.access import bag_info
from rostools.cli.tf.echo import WHOLE_RECORDING_NS
from rostools.cli.tf.shared import open_feed
from tests.support.env import CORPUS, needs_corpus, run_cli
from tests.support.tf2peer import ask_tf2, needs_tf2

pytestmark = [needs_corpus, needs_tf2]

ROS1 = CORPUS / "ros1"
TURTLES = ["world", "turtle1", "turtle2", "carrot"]
#: bag -> the frame pairs looked up (tf echo A B: B's pose in A).
BAGS = {
    "rosbag.js/example.bag": [(a, b) for a in TURTLES for b in TURTLES if a != b],
    "rosbag.js/example-lz4.bag": [("world", "carrot"), ("turtle2", "turtle1")],
    "rosbag.js/example-bz2.bag": [("carrot", "turtle2"), ("world", "turtle1")],
    "webviz/example.lz4.bag": [("turtle1", "world"), ("carrot", "world")],
    "webviz/only-a-cube.bag": [("parent_frame", "child_frame")],
    "webviz/only-a-cube-2019-06.bag": [("cruise_frame", "chassis")],
}


def _echo(path: Path, pair: tuple[str, str], *args: str) -> tuple[list[dict[str, Any]], str]:
    proc = run_cli("tf", "echo", *pair, "-b", str(path), "-F", "json", *args, timeout=120)
    assert proc.returncode == 0, proc.stderr
    return [json.loads(line) for line in proc.stdout.splitlines()], proc.stderr


def _shift(path: Path) -> int:
    """tf2_py's offset for a bag (``tf2_oracle.py``): its times near 0, where float seconds
    are exact to the ns (a second before the earliest stamp)."""
    with open_feed(path) as feed:
        stamps = [t.stamp_ns for b in feed.batches() if not b.static for t in b.transforms]
    return (min(stamps) // 1_000_000_000 - 1) * 1_000_000_000


def _seconds(ns: int) -> str:
    """``--at``'s absolute form, to the ns (0: the latest)."""
    secs, nsecs = divmod(ns, 1_000_000_000)
    return f"{secs}.{nsecs:09d}"


def _same(ours: dict[str, Any], tf2: dict[str, Any], where: str) -> None:
    stamp, seven = tf2["ok"]
    assert ours["stamp_ns"] == stamp, where
    assert [*ours["translation"], *ours["rotation"]] == pytest.approx(seven, abs=1e-9), where


@pytest.mark.parametrize("name", list(BAGS))
def test_any_time_of_the_recording_answers_as_tf2(name: str) -> None:
    path = ROS1 / name
    info = bag_info(path)
    assert info.start_ns is not None and info.end_ns is not None
    rng = random.Random(name)
    span = info.end_ns - info.start_ns
    with open_feed(path) as feed:
        stamps = sorted({t.stamp_ns for b in feed.batches() for t in b.transforms})
    # times inside the recording (where every edge has data on both sides, or exactly on it)
    offsets = sorted(rng.randrange(span // 10, span - span // 10 + 1) for _ in range(100))
    pairs = BAGS[name]
    ops: list[list[Any]] = [["shift", _shift(path)], ["bag", str(path), None]]
    asked: list[tuple[tuple[str, str], int]] = []
    for i, offset in enumerate(offsets):
        pair = pairs[i % len(pairs)]
        at = info.start_ns + offset
        if len(stamps) == 1:  # one transform: at its stamp and at the latest, 100 times
            at = stamps[0] if i % 2 else 0
        ops.append(["lookup", *pair, at])
        asked.append((pair, offset))
    want = ask_tf2(WHOLE_RECORDING_NS, ops)
    compared = 0
    for pair in pairs:
        mine = [(i, o) for i, (p, o) in enumerate(asked) if p == pair]
        for i, offset in mine:
            assert "ok" in want[i], f"{name} {pair} +{offset}: tf2 says {want[i]}"
        ats = [_seconds(ops[i + 2][3]) for i, _ in mine]
        got, _ = _echo(path, pair, *[a for t in ats for a in ("--at", t)])
        assert len(got) == len(mine)
        for (i, offset), answer in zip(mine, got, strict=True):
            _same(answer, want[i], f"{name} {pair} at +{offset}")
            assert (answer["frame_id"], answer["child_frame_id"]) == pair
            compared += 1
    assert compared == 100


@pytest.mark.parametrize("name", ["rosbag.js/example.bag", "webviz/example.lz4.bag"])
def test_stepping_through_a_recording_answers_as_tf2_at_each_step(name: str) -> None:
    path = ROS1 / name
    info = bag_info(path)
    assert info.start_ns is not None and info.end_ns is not None
    pair = ("turtle2", "carrot")
    got, stderr = _echo(path, pair, "-r", "5")
    ops: list[list[Any]] = [["shift", _shift(path)]]
    tick = info.start_ns
    while tick <= info.end_ns:
        ops += [["bag", str(path), tick], ["lookup", *pair, 0]]
        tick += 200_000_000
    want = ask_tf2(10 * 1_000_000_000, ops)
    first = next(i for i, w in enumerate(want) if "ok" in w)
    answered = [w for w in want[first:] if "ok" in w]
    failed = [w for w in want[first:] if "error" in w]
    assert len(got) == len(answered) > 50
    for i, (ours, tf2) in enumerate(zip(got, answered, strict=True)):
        _same(ours, tf2, f"{name} step {i}")
    # after the first answer, a step that fails is one line on stderr, as tf_echo goes on
    assert len(stderr.splitlines()) == len(failed)


def test_relative_times_count_from_the_start_of_the_recording() -> None:
    path = ROS1 / "rosbag.js/example.bag"
    info = bag_info(path)
    assert info.start_ns is not None
    pair = ("world", "turtle1")
    relative, _ = _echo(path, pair, "--at", "+2.5")
    absolute, _ = _echo(path, pair, "--at", _seconds(info.start_ns + 2_500_000_000))
    assert relative == absolute and relative[0]["stamp_ns"] == info.start_ns + 2_500_000_000


@pytest.mark.parametrize(
    ("args", "code", "words"),
    [
        (["a", "b", "-b", "{corpus}/embag/test.bag"], 3, "holds no /tf"),
        (["world", "nowhere", "-b", "{turtles}"], 3, "does not exist"),
        (["world", "carrot", "-b", "{turtles}", "--at", "-5"], 1, "into the past"),
        (["world", "carrot", "-b", "{turtles}", "--at", "5"], 1, "counts from the recording"),
        (["world", "carrot", "-b", "{turtles}", "--at", "soon"], 2, "--at takes seconds"),
        (["world", "carrot", "-b", "{turtles}", "--at", "+1", "-n", "2"], 2, "-n does not"),
        (["world", "carrot", "-b", "{turtles}", "-r", "0"], 2, "--rate must be above 0"),
        (["world", "carrot", "-b", "{turtles}", "--timeout", "1"], 2, "does not apply"),
        (["", "carrot", "-b", "{turtles}"], 2, "cannot be empty"),
    ],
)
def test_bad_input_from_a_bag_is_one_line(args: list[str], code: int, words: str) -> None:
    turtles = str(ROS1 / "rosbag.js/example.bag")
    argv = [a.replace("{corpus}", str(ROS1)).replace("{turtles}", turtles) for a in args]
    proc = run_cli("tf", "echo", *argv)
    assert proc.returncode == code, proc.stderr
    assert words in proc.stderr and len(proc.stderr.splitlines()) == 1
    assert proc.stdout == ""
