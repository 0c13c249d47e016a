"""``/topic/field`` names: which topic a name means, and why a field of a known topic is not one."""

from __future__ import annotations

from rostools.msgs.store import TypeStore
from rostools.msgs.topicpath import field_problem, split_field

TYPES = {"/v": "geometry_msgs/Point", "/odom": "nav_msgs/Odometry", "/any": "*"}


def test_a_field_of_a_published_topic_splits() -> None:
    store = TypeStore.default()
    ref = split_field("/odom/pose/pose/position/x", TYPES, store)
    assert ref is not None and (ref.topic, ref.field) == ("/odom", "pose/pose/position/x")
    assert field_problem("/odom/pose/pose/position/x", TYPES, store) is None


def test_a_misspelt_field_is_named() -> None:
    """It used to say only that /v/q 'does not appear to be published yet'."""
    store = TypeStore.default()
    assert split_field("/v/q", TYPES, store) is None
    problem = field_problem("/v/q", TYPES, store)
    assert problem is not None and problem.startswith("/v is geometry_msgs/Point: ")
    assert "q" in problem
    assert field_problem("/nobody/x", TYPES, store) is None  # no prefix is a topic
    assert field_problem("/any/x", TYPES, store) is None  # a type unknown here is not judged
