"""The pure parts of ``tf frames``, ``tf monitor`` and ``tf pub``: edges as tf2's buffer keeps
them, tf_monitor's counts, the tree drawn, and static_transform_publisher's arguments.

tf2 itself is the truth for edges (``tests/interop/test_tf_tools_interop.py`` feeds both the
same transforms); these pin the rules one by one.
"""

from __future__ import annotations

import math

import pytest

from rostools.cli.tf.frames import edge_label, frames_dot, frames_text
from rostools.cli.tf.monitor import report_text
from rostools.cli.tf.pub import parse
from rostools.errors import UsageError
from rostools.tf.edges import Edges, refusal
from rostools.tf.monitor import Monitor
from rostools.tf.records import Stamped

S = 1_000_000_000
UNIT = (0.0, 0.0, 0.0, 1.0)


def tf(parent: str, child: str, sec: float, rotation: tuple[float, ...] = UNIT) -> Stamped:
    return Stamped(parent, child, round(sec * S), (1.0, 2.0, 3.0), rotation)  # type: ignore[arg-type]


def test_a_dynamic_edge_keeps_its_cache_time_drops_old_and_repeated_stamps() -> None:
    edges = Edges()
    for t, who in [(100, "n1"), (100, "n2"), (101, "n3"), (85, "n4"), (111.5, "n5")]:
        edges.add([tf("a", "b", t)], who, static=False)
    edges.add([tf("x", "b", 105)], "n6", static=False)
    (edge,) = edges.edges()
    # 100 and 101 fell out of the 10 s behind 111.5; 85 was too old to take; the second 100
    # repeated a stamp: tf2 keeps the first and names neither n2 nor n4
    assert edge.stamps == [105 * S, int(111.5 * S)]
    assert edge.parent == "a"  # the newest entry's
    assert edge.broadcaster == "n6"  # the last that was taken
    assert edge.rate == pytest.approx(2 / 6.5)
    assert edge.span == pytest.approx(6.5)


def test_a_static_edge_reads_as_tf2s_static_cache() -> None:
    edges = Edges()
    edges.add([tf("a", "s", 5)], "st", static=True)
    edges.add([tf("a", "s", 7)], "dyn", static=False)  # its cache stays static
    (edge,) = edges.edges()
    assert (edge.length, edge.newest_ns, edge.oldest_ns, edge.rate) == (1, 0, 0, 10000.0)
    assert edge.broadcaster == "dyn"


@pytest.mark.parametrize(
    ("t", "why"),
    [
        (tf("a", "a", 1), "TF_SELF_TRANSFORM"),
        (tf("", "a", 1), "TF_NO_FRAME_ID"),
        (tf("a", "", 1), "TF_NO_CHILD_FRAME_ID"),
        (tf("a", "b", 1, (0.0, 0.0, 0.0, 2.0)), "TF_DENORMALIZED_QUATERNION"),
        (tf("a", "b", 1, (math.nan, 0.0, 0.0, 1.0)), "TF_NAN_INPUT"),
    ],
)
def test_what_tf2_refuses_is_counted_not_kept(t: Stamped, why: str) -> None:
    edges = Edges()
    edges.add([t], "n", static=False)
    assert refusal(t) == why
    assert edges.refused == {why: 1} and not edges.by_child


def tree() -> Edges:
    edges = Edges()
    edges.add([tf("base", "odom", 1), tf("odom", "robot", 1)], "/mover", static=False)
    edges.add([tf("base", "odom", 1.5), tf("odom", "robot", 1.5)], "/mover", static=False)
    edges.add([tf("base", "laser", 0)], "/stp", static=True)
    return edges


def test_the_text_tree_hangs_each_child_under_its_parent() -> None:
    assert frames_text(tree()).splitlines() == [
        "base",
        "├── laser  [/stp, static]",
        "└── odom  [/mover, 4.0 Hz, 0.500 s buffered]",
        "    └── robot  [/mover, 4.0 Hz, 0.500 s buffered]",
    ]


def test_a_loop_is_drawn_once_where_it_closes() -> None:
    edges = Edges()
    edges.add([tf("a", "b", 1), tf("b", "a", 1)], "/n", static=False)
    # one entry over tf2's 0.1 ms floor: 10000 Hz, as view_frames says too
    assert frames_text(edges).splitlines() == [
        "a",
        "└── b  [/n, 10000.0 Hz, 0.000 s buffered]",
        "    └── a  [/n, 10000.0 Hz, 0.000 s buffered]",
    ]


def test_a_broadcaster_a_bag_did_not_keep_is_shown_as_tf_monitor_names_it() -> None:
    edges = Edges()
    edges.add([tf("world", "turtle1", 1)], "", static=False)
    assert edges.by_child["turtle1"].broadcaster == ""  # as tf2 keeps it, and JSON gives it
    assert frames_text(edges).splitlines()[1].startswith("└── turtle1  [unknown_publisher, ")
    mon = Monitor()
    mon.add(S, "", False, [tf("world", "turtle1", 1)])
    text = report_text(mon.report(), None, None)
    assert "Frame: turtle1 published by unknown_publisher Average Delay: 0 " in text
    assert "Node: unknown_publisher 1e+08 Hz," in text  # tf_monitor's count over a 10 ns floor


def test_the_dot_has_view_frames_labels_and_edges() -> None:
    dot = frames_dot(tree(), 7 * S)
    assert '"base" -> "odom" [label="Broadcaster: /mover\\nAverage rate: 4.0\\n' in dot
    assert '"base" -> "laser"' in dot and '"odom" -> "robot"' in dot
    assert '"Recorded at time: 7.000" -> "base";' in dot
    assert edge_label(tree().by_child["laser"]) == [
        "Broadcaster: /stp",
        "Average rate: 10000.0",
        "Buffer length: 0.0",
        "Most recent transform: 0.0",
        "Oldest transform: 0.0",
    ]


def test_monitor_counts_delay_per_frame_and_rate_per_broadcaster() -> None:
    mon = Monitor()
    for i in range(11):  # 10 Hz for 1 s, each received 20 ms after its stamp
        stamp = 100 + i / 10
        mon.add(round((stamp + 0.02) * S), "/mover", False, [tf("base", "odom", stamp)])
    mon.add(200 * S, "/stp", True, [tf("base", "laser", 0)])
    report = mon.report()
    (odom,) = [f for f in report["frames"] if f["frame"] == "odom"]  # type: ignore[attr-defined]
    assert odom["average_delay"] == pytest.approx(0.02) and odom["broadcaster"] == "/mover"
    broadcasters = report["broadcasters"]
    assert isinstance(broadcasters, list)
    mover, stp = broadcasters
    assert mover["rate"] == pytest.approx(11 / 1.0)  # tf_monitor's count over span
    assert stp["static"] and stp["rate"] is None
    text = report_text(report, None, None)
    assert "Frame: odom published by /mover Average Delay: 0.02 Max Delay: 0.02" in text
    assert "Node: /mover 11 Hz, Average Delay: 0.02 Max Delay: 0.02" in text
    assert "Node: /stp (static) Average Delay: 0 Max Delay: 0" in text


def test_monitor_walks_the_chain_through_the_common_parent() -> None:
    mon = Monitor()
    mon.add(S, "/m", False, [tf("base", "odom", 1), tf("odom", "robot", 1)])
    mon.add(S, "/s", True, [tf("base", "laser", 0)])
    assert mon.chain("base", "robot") == ["base", "odom", "robot"]
    assert mon.chain("laser", "robot") == ["laser", "base", "odom", "robot"]
    assert mon.chain("robot", "nowhere") is None
    assert mon.sample_chain(["base", "odom", "robot"], 3 * S) == pytest.approx(2.0)
    report = mon.report(["base", "odom", "robot"])
    assert [f["frame"] for f in report["frames"]] == ["odom", "robot"]  # type: ignore[attr-defined]
    assert report["net_delay"] == {"average": 2.0, "max": 2.0}


def test_pub_reads_both_forms_as_static_transform_publisher() -> None:
    t = parse(["1", "-2", "3.5", "0.3", "0.2", "0.1", "base", "child"], 5)
    assert (t.parent, t.child, t.stamp_ns, t.translation) == ("base", "child", 5, (1, -2, 3.5))
    # yaw pitch roll: tf2's setRPY(roll, pitch, yaw)
    cy, sy = math.cos(0.15), math.sin(0.15)
    cp, sp = math.cos(0.1), math.sin(0.1)
    cr, sr = math.cos(0.05), math.sin(0.05)
    assert t.rotation == pytest.approx(
        (
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy,
        ),
        abs=1e-15,
    )
    q = parse(["0", "0", "0", "0", "0", "0.6", "0.8", "a", "b"], 0)
    assert q.rotation == (0.0, 0.0, 0.6, 0.8)


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["1", "2", "3"], "8 or 9 arguments, not 3"),
        (["1", "2", "x", "0", "0", "0", "a", "b"], "not a number: x"),
        (["1", "2", "nan", "0", "0", "0", "a", "b"], "not a finite number: nan"),
        (["0", "0", "0", "0", "0", "0", "a", "a"], "target_frame and source frame are the same"),
        (["0", "0", "0", "0.1", "0.2", "0.3", "0.4", "a", "b"], "TF_DENORMALIZED_QUATERNION"),
    ],
)
def test_pub_refuses_what_names_no_transform(args: list[str], words: str) -> None:
    with pytest.raises(UsageError, match=words):
        parse(args, 0)
