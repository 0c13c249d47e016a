"""The TF feed (``cli/tf/shared.py``) over the corpus bags that hold ``/tf``."""

from __future__ import annotations

import pytest

from rostools.cli.tf.shared import open_feed
from rostools.errors import NotFoundError
from tests.support.env import CORPUS, needs_corpus

pytestmark = needs_corpus

ROS1 = CORPUS / "ros1"
TURTLES = ["rosbag.js/example.bag", "rosbag.js/example-lz4.bag", "rosbag.js/example-bz2.bag"]


@pytest.mark.parametrize("name", [*TURTLES, "webviz/example.lz4.bag"])
def test_turtle_bags_give_every_tf_message_once(name: str) -> None:
    with open_feed(ROS1 / name) as feed:
        batches = list(feed.batches())
        assert feed.start_ns is not None and feed.end_ns is not None
        assert all(feed.start_ns <= b.received_ns <= feed.end_ns for b in batches)
    assert len(batches) == 2689
    assert [b.received_ns for b in batches] == sorted(b.received_ns for b in batches)
    statics = [b for b in batches if b.static]
    assert [(t.parent, t.child) for b in statics for t in b.transforms] == [("turtle1", "carrot")]
    pairs = {(t.parent, t.child) for b in batches for t in b.transforms}
    assert pairs == {("world", "turtle1"), ("world", "turtle2"), ("turtle1", "carrot")}


def test_a_bag_that_kept_callerids_names_each_broadcaster() -> None:
    with open_feed(ROS1 / "rosbag.js/example.bag") as feed:
        by_child = {t.child: b.broadcaster for b in feed.batches() for t in b.transforms}
    assert by_child["turtle1"] == "/turtle1_tf_broadcaster"
    assert by_child["turtle2"] == "/turtle2_tf_broadcaster"
    assert by_child["carrot"].startswith("/static_transform_publisher_")


def test_the_feed_stops_at_an_end_time() -> None:
    with open_feed(ROS1 / "rosbag.js/example.bag") as feed:
        assert feed.start_ns is not None
        end = feed.start_ns + 1_000_000_000
        batches = list(feed.batches(end_ns=end))
    assert batches and all(b.received_ns <= end for b in batches)
    assert len(batches) < 2689


def test_a_bag_without_tf_is_not_found() -> None:
    with pytest.raises(NotFoundError, match="holds no /tf"), open_feed(ROS1 / "embag/test.bag"):
        pass


def test_frame_names_complete_from_a_bag() -> None:
    from rostools.cli.completer import Completer

    bag = str(ROS1 / "rosbag.js/example.bag")
    words = ["rostools", "tf", "echo", "-b", bag, "turtle1", "t"]
    got = [v for v, _ in Completer(words, len(words) - 1, 5).complete()]
    assert got == ["turtle1", "turtle2"]
    words = ["rostools", "tf", "echo", f"--bag={bag}", ""]
    got = [v for v, _ in Completer(words, len(words) - 1, 5).complete()]
    assert got == ["carrot", "turtle1", "turtle2", "world"]
