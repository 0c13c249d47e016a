"""Messages from YAML values, with rostopic pub semantics and precise errors."""

from __future__ import annotations

import pytest
import yaml

from rostools.errors import UsageError
from rostools.msgs.codec import Codec
from rostools.msgs.fill import FieldValueError, Filler, parse_yaml_args
from rostools.msgs.message import Duration, Time
from rostools.msgs.store import BuiltinSource, TypeStore

CODEC = Codec.of(TypeStore([BuiltinSource()]))
NOW = Time(100, 5)


def fill(type_name: str, *args: str) -> object:
    return Filler(CODEC, NOW).message(type_name, [yaml.safe_load(a) for a in args])


def test_mapping_fills_by_name_and_keeps_defaults() -> None:
    m = fill("geometry_msgs/Twist", "{linear: {x: 1}}")
    assert m.linear.x == 1.0 and m.angular.z == 0.0  # type: ignore[attr-defined]


def test_positional_values_and_nested_lists() -> None:
    m = fill("geometry_msgs/Vector3", "1", "2", "3.5")
    assert (m.x, m.y, m.z) == (1.0, 2.0, 3.5)  # type: ignore[attr-defined]
    p = fill("geometry_msgs/Pose", "[1, 2, 3]", "[0, 0, 0, 1]")
    assert p.orientation.w == 1.0  # type: ignore[attr-defined]


def test_now_auto_and_time_forms() -> None:
    m = fill("geometry_msgs/PointStamped", "{header: auto}")
    assert m.header.stamp == NOW  # type: ignore[attr-defined]
    assert fill("std_msgs/Time", "now").data == NOW  # type: ignore[attr-defined]
    assert fill("std_msgs/Time", "1500000000").data == Time(1, 500000000)  # type: ignore[attr-defined]
    assert fill("std_msgs/Time", "{data: {secs: 3, nsecs: 4}}").data == Time(3, 4)  # type: ignore[attr-defined]
    assert fill("std_msgs/Duration", "[-1, 0]").data == Duration(-1, 0)  # type: ignore[attr-defined]


@pytest.mark.parametrize(
    ("type_name", "args", "message"),
    [
        ("std_msgs/Int8", ["300"], "field data: expected int8 in \\[-128, 127\\], got 300"),
        ("std_msgs/Int32", ["'x'"], "field data: expected an integer \\(int32\\)"),
        ("std_msgs/String", ["5"], "field data: expected a string, got 5"),
        (
            "geometry_msgs/Twist",
            ["{linear: {w: 1}}"],
            "no field named linear.w in geometry_msgs/Vector3",
        ),
        ("geometry_msgs/Vector3", ["1", "2"], "takes 3 values in field order, got 2"),
        ("sensor_msgs/NavSatFix", ["{position_covariance: [1]}"], "expected 9 elements, got 1"),
        (
            "geometry_msgs/PoseArray",
            ["{poses: [{position: {x: a}}]}"],
            "field poses\\[0\\].position.x",
        ),
        ("std_msgs/Bool", ["2"], "expected a bool"),
        ("std_msgs/Header", ["{stamp: auto}"], "field stamp: expected a time"),
    ],
)
def test_errors_name_the_field_path(type_name: str, args: list[str], message: str) -> None:
    with pytest.raises(FieldValueError, match=message):
        fill(type_name, *args)


def test_filled_messages_serialize() -> None:
    m = fill("sensor_msgs/Image", "{height: 1, width: 2, data: [1, 2, 3], encoding: mono8}")
    assert m.serialize()[-7:] == b"\x03\x00\x00\x00\x01\x02\x03"  # type: ignore[attr-defined]


def test_yaml_arguments() -> None:
    assert parse_yaml_args(["1", "{a: [1, 2]}", "", "'x'", "1e3"]) == [
        1,
        {"a": [1, 2]},
        "",
        "x",
        "1e3",
    ]
    with pytest.raises(UsageError, match=r"bad YAML in argument '\{a: 1': .* \(line 2, column 1\)"):
        parse_yaml_args(["{a: 1"])


@pytest.mark.parametrize(
    ("args", "tail"),
    [
        ([1, 2], "f18 f19 ... (980 more: rostools msg show big/Wide)"),
        ([{"nope": 1}], "f18, f19, ... (980 more: rostools msg show big/Wide)"),
    ],
)
def test_a_hint_names_at_most_twenty_fields(args: list[object], tail: str) -> None:
    """The hint of a type of 100,000 fields was a line of 700 KB: twenty, then how many more."""
    fields = "".join(f"int32 f{i}\n" for i in range(1000))
    store = TypeStore([BuiltinSource()]).with_definition("big/Wide", fields)
    with pytest.raises(FieldValueError) as err:
        Filler(Codec.of(store), NOW).message("big/Wide", args)
    assert (err.value.hint or "").endswith(tail)
    assert len(err.value.hint or "") < 300
