"""``tf frames``, ``tf monitor`` and ``tf pub`` beside tf2's own tools, on both masters.

- edges: tf2's ``BufferCore`` (``tf2_py``) fed the same transforms, or the same bag through
  rosbag, gives the same ``allFramesAsYAML`` as ``rostools.tf.edges``;
- frames: what ``view_frames`` draws (its ``frames.gv``) is what ``tf frames -o x.dot`` draws,
  edge for edge, with each edge's broadcaster;
- monitor: a broadcaster's rate is ``tf_monitor``'s within a tolerance that holds under load;
- pub: a real tf2 listener sees ``tf pub``'s transforms, two at once, with the values
  ``static_transform_publisher`` sends for the same arguments, to 1e-12.
"""

from __future__ import annotations

import json
import random
import re
import signal
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml

from rostools.tf.edges import DEFAULT_CACHE_NS, Edges
from rostools.tf.records import Stamped
from tests.conftest import MasterInfo
from tests.support.env import CORPUS, SYSTEM_PYTHON, needs_corpus, needs_ros1, run_cli
from tests.support.load import scaled
from tests.support.procs import (
    Proc,
    publishers,
    start_cli,
    start_ros1_node,
    wait_for,
)
from tests.support.reap import run
from tests.support.tf2peer import ask_tf2, needs_tf2, tf2_missing

pytestmark = [pytest.mark.interop, needs_ros1]

STP = "/usr/lib/tf2_ros/static_transform_publisher"
TF_MONITOR = "/usr/lib/tf/tf_monitor"
VIEW_FRAMES = "/usr/lib/tf2_tools/view_frames.py"


def _tools_missing() -> str | None:
    for tool in (STP, TF_MONITOR, VIEW_FRAMES):
        if not Path(tool).exists():
            return f"{tool} is not installed (scripts/install-ros1-peers.sh)"
    return tf2_missing()


#: tf2_py and the three tools of tf2_ros, tf2_tools and tf.
needs_tools = pytest.mark.skipif((_why := _tools_missing()) is not None, reason=_why or "")


def tf2_yaml(ops: list[list[Any]]) -> dict[str, dict[str, object]]:
    """tf2's ``allFramesAsYAML`` after ``ops`` (``tf2_oracle.py``), parsed."""
    answers = ask_tf2(DEFAULT_CACHE_NS, [*ops, ["yaml"]])
    parsed = yaml.safe_load(answers[-1]["yaml"])
    return parsed if isinstance(parsed, dict) else {}


def ours_as_tf2(data: list[dict[str, object]]) -> dict[str, dict[str, object]]:
    """``tf frames``' edges keyed and rounded as tf2's YAML has them."""
    return {
        str(e["child"]): {
            "parent": e["parent"],
            "broadcaster": e["broadcaster"],
            "rate": round(float(e["rate"]), 3),  # type: ignore[arg-type]
            "most_recent_transform": round(float(e["most_recent_transform"]), 3),  # type: ignore[arg-type]
            "oldest_transform": round(float(e["oldest_transform"]), 3),  # type: ignore[arg-type]
            "buffer_length": round(float(e["buffer_length"]), 3),  # type: ignore[arg-type]
        }
        for e in data
    }


def assert_same_tree(ours: dict[str, dict[str, object]], tf2: dict[str, dict[str, object]]) -> None:
    """Same frames, parents and broadcasters; numbers within tf2's last printed digit."""
    assert sorted(ours) == sorted(tf2)
    for child, theirs in tf2.items():
        mine = ours[child]
        for key in ("parent", "broadcaster"):
            assert mine[key] == theirs[key], (child, key)
        for key in ("rate", "most_recent_transform", "oldest_transform", "buffer_length"):
            assert mine[key] == pytest.approx(theirs[key], abs=1.5e-3), (child, key)


@needs_tf2
def test_edges_equal_tf2s_buffer_for_the_same_transforms() -> None:
    """Random feeds: repeats, stamps out of order and too old, refusals, statics, re-parenting."""
    rng = random.Random(36)
    frames = ["map", "odom", "base", "laser", "cam", "arm"]
    ops: list[list[Any]] = []
    ours = Edges()
    for _ in range(3000):
        parent, child = rng.sample(frames, 2)
        if rng.random() < 0.02:
            child = parent  # refused by both
        stamp_ns = rng.randrange(0, 40_000) * 1_000_000  # ms: tf2 prints three decimals
        q = [0.0, 0.0, 0.0, 1.0] if rng.random() > 0.02 else [0.0, 0.0, 0.0, 2.0]
        who = rng.choice(["/a", "/b", ""])
        static = child == "laser"
        ops.append(["set", parent, child, stamp_ns, [1.0, 2.0, 3.0, *q], static, who])
        t = Stamped(parent, child, stamp_ns, (1.0, 2.0, 3.0), tuple(q))  # type: ignore[arg-type]
        ours.add([t], who, static)
    tf2 = tf2_yaml(ops)
    assert len(tf2) >= 4
    assert_same_tree(ours_as_tf2([e.to_data() for e in ours.edges()]), tf2)


@needs_tf2
@needs_corpus
@pytest.mark.parametrize("name", ["rosbag.js/example.bag", "webviz/example.lz4.bag"])
def test_a_bags_tree_is_the_one_tf2_holds_at_its_end(name: str, cli_env: dict[str, str]) -> None:
    bag = CORPUS / "ros1" / name
    done = run_cli("--format", "json", "tf", "frames", "-b", str(bag), env=cli_env)
    assert done.returncode == 0, done.stderr
    ours = json.loads(done.stdout)
    tf2 = tf2_yaml([["bag", str(bag)]])
    assert set(tf2) == {"turtle1", "turtle2", "carrot"}
    assert_same_tree(ours_as_tf2(ours["edges"]), tf2)
    assert ours["frames"] == ["carrot", "turtle1", "turtle2", "world"]


# live, on both masters ---------------------------------------------------------------------


@pytest.fixture
def tf_graph(any_master: MasterInfo) -> Iterator[tuple[MasterInfo, list[str]]]:
    """Two static_transform_publishers and a rospy broadcaster of two moving frames.

    Yields the master and the broadcasters' node names, once all three are heard.
    """
    env = any_master.ros_env
    procs: list[Proc] = []
    statics: list[str] = []
    try:
        # one at a time, so that each anonymous name is known to be its frame's broadcaster
        for args in (
            ["0.1", "0", "0.2", "0", "0", "0", "base", "laser"],
            ["0", "0", "0.5", "0", "0", "0", "1", "laser", "laser_optical"],
        ):
            procs.append(Proc([STP, *args], env=env))
            wait_for(lambda: len(publishers(any_master.uri, "/tf_static")) > len(statics), 20,
                     "a static_transform_publisher")  # fmt: skip
            (new,) = set(publishers(any_master.uri, "/tf_static")) - set(statics)
            statics.append(new)
        mover = start_ros1_node("tf_mover.py", ["50", "map", "odom", "odom", "base"], env)
        procs.append(mover)
        mover.expect("broadcasting", 30)
        yield any_master, [*statics, "/tf_mover"]
    finally:
        for p in procs:
            p.stop()


def view_frames_edges(gv: str) -> set[tuple[str, str, str]]:
    """(parent, child, broadcaster) of each edge of a ``frames.gv``."""
    found = re.findall(r'^"([^"]+)" -> "([^"]+)"\[label=" Broadcaster: ([^\\]+)\\n', gv, re.M)
    return set(found)


def our_edges(dot: str) -> set[tuple[str, str, str]]:
    """(parent, child, broadcaster) of each edge ``tf frames -o x.dot`` drew."""
    found = re.findall(r'^  "([^"]+)" -> "([^"]+)" \[label="Broadcaster: ([^\\]+)\\n', dot, re.M)
    return set(found)


@needs_tools
def test_tf_frames_draws_the_edges_view_frames_finds(
    tf_graph: tuple[MasterInfo, list[str]], tmp_path: Path
) -> None:
    info, broadcasters = tf_graph
    cwd = tmp_path / "view_frames"
    cwd.mkdir()
    mine = start_cli("tf", "frames", "-w", "5", "-o", str(tmp_path / "x.dot"), env=info.cli_env)
    theirs = run([SYSTEM_PYTHON, VIEW_FRAMES], env=info.ros_env, cwd=cwd, timeout=scaled(90))
    try:
        assert _wait_exit(mine, 60) == 0, mine.output()
    finally:
        mine.stop()
    assert theirs.returncode == 0, theirs.stderr[-2000:]
    expected = view_frames_edges((cwd / "frames.gv").read_text())
    static_a, static_b, mover = broadcasters
    assert {(p, c) for p, c, _ in expected} == {
        ("map", "odom"),
        ("odom", "base"),
        ("base", "laser"),
        ("laser", "laser_optical"),
    }
    assert {b for *_, b in expected} == {static_a, static_b, mover}
    assert our_edges((tmp_path / "x.dot").read_text()) == expected


def _wait_exit(proc: Proc, timeout: float) -> int:
    """``proc``'s exit code once it ends on its own."""
    return proc.popen.wait(scaled(timeout))


@needs_tools
def test_tf_monitor_rates_agree_with_tf_monitors(tf_graph: tuple[MasterInfo, list[str]]) -> None:
    info, (static_a, static_b, mover) = tf_graph
    theirs = Proc([TF_MONITOR], env=info.ros_env)
    mine = start_cli("--format", "json", "tf", "monitor", "-n", "8", env=info.cli_env)
    try:
        assert _wait_exit(mine, 60) == 0, mine.output()
        reports = [json.loads(line) for line in mine.output()[0].splitlines()]
        theirs.signal(signal.SIGINT)
        out, _ = theirs.output()
    finally:
        theirs.stop()
    rates = re.findall(r"^Node: unknown_publisher ([0-9.e+]+) Hz", out, re.M)
    assert rates, out[-2000:]
    their_rate = float(rates[-1])
    last = {b["broadcaster"]: b for b in reports[-1]["broadcasters"]}
    assert set(last) == {static_a, static_b, mover}
    assert last[static_a]["static"] and last[static_a]["rate"] is None
    # both heard the same 50 Hz broadcaster over seconds of one another: under load rospy
    # sends late, for both
    assert last[mover]["rate"] == pytest.approx(their_rate, rel=0.2)
    frames = {f["frame"]: f["broadcaster"] for f in reports[-1]["frames"]}
    assert frames == {"odom": mover, "base": mover, "laser": static_a, "laser_optical": static_b}


@needs_tools
def test_tf_pub_is_seen_by_tf2_with_static_transform_publishers_values(
    any_master: MasterInfo,
) -> None:
    info = any_master
    rpy = ["0.25", "-1.5", "3", "0.3", "-0.2", "1.1"]
    quat = ["1", "2", "3", "0", "0.6", "0", "0.8"]
    procs = [
        Proc([STP, *rpy, "base", "theirs_rpy"], env=info.ros_env),
        Proc([STP, *quat, "base", "theirs_q"], env=info.ros_env),
    ]
    ours = [
        start_cli("tf", "pub", *rpy, "base", "ours_rpy", env=info.cli_env),
        start_cli("tf", "pub", *quat, "base", "ours_q", env=info.cli_env),
    ]
    try:
        wait_for(lambda: len(publishers(info.uri, "/tf_static")) == 4, 30, "four publishers")
        pairs = ["base", "theirs_rpy", "base", "theirs_q", "base", "ours_rpy", "base", "ours_q"]
        lookup = start_ros1_node("tf_lookup.py", pairs, info.ros_env)
        procs.append(lookup)
        assert _wait_exit(lookup, 60) == 0, lookup.output()
        seen = {d["child"]: d for d in map(json.loads, lookup.output()[0].splitlines())}
        for kind in ("rpy", "q"):
            a, b = seen[f"theirs_{kind}"], seen[f"ours_{kind}"]
            assert a["t"] == pytest.approx(b["t"], abs=1e-12)
            assert a["q"] == pytest.approx(b["q"], abs=1e-12)
        # Ctrl-C or SIGTERM: a clean end, and the publisher is gone from the master
        for proc, sig in zip(ours, (signal.SIGINT, signal.SIGTERM), strict=True):
            proc.signal(sig)
            assert _wait_exit(proc, 30) == 0, proc.output()
        wait_for(lambda: len(publishers(info.uri, "/tf_static")) == 2, 15, "ours unregistered")
    finally:
        for proc in ours + procs:
            proc.stop()
