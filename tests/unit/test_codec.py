"""Generated (de)serialisers: bytes from the ROS 1 spec, round trips, hostile input."""

from __future__ import annotations

import pytest
from hypothesis import given, settings, strategies as st

from rostools.msgs.codec import Codec, DecodeError, EncodeError
from rostools.msgs.message import Duration, Time
from rostools.msgs.store import BuiltinSource, TypeStore
from tests.support.randmsg import RandomMessages

CODEC = Codec.of(TypeStore([BuiltinSource()]))


def msg(type_name: str, *args: object, **kwargs: object) -> object:
    return CODEC.message_class(type_name)(*args, **kwargs)


def test_bytes_from_the_protocol_document() -> None:
    dim = msg("std_msgs/MultiArrayDimension", "x", 2, 2)
    layout = msg("std_msgs/MultiArrayLayout", [dim], 0)
    arr = msg("std_msgs/Int32MultiArray", layout, [1, -1])
    assert arr.serialize() == bytes.fromhex(  # type: ignore[attr-defined]
        "01000000 01000000 78 02000000 02000000 00000000 02000000 01000000 ffffffff"
    )
    assert msg("std_msgs/Duration", Duration(-1, 0)).serialize() == bytes.fromhex(  # type: ignore[attr-defined]
        "ffffffff00000000"
    )
    assert msg("std_msgs/String", "hé").serialize() == bytes.fromhex("0300000068c3a9")  # type: ignore[attr-defined]
    assert len(msg("sensor_msgs/NavSatFix").serialize()) == 116  # type: ignore[attr-defined]


def test_point_stamped_frame() -> None:
    wire = bytes.fromhex(
        "01000000 00f15365 f4010000 03000000 6d6170"
        "000000000000f03f 00000000000000c0 0000000000004240"
    )
    m = CODEC.decode("geometry_msgs/PointStamped", wire)
    assert (m.header.seq, m.header.stamp, m.header.frame_id) == (1, Time(1700000000, 500), "map")
    assert (m.point.x, m.point.y, m.point.z) == (1.0, -2.0, 36.0)
    assert m.serialize() == wire


@pytest.mark.parametrize(
    "name",
    [
        "sensor_msgs/Image",
        "sensor_msgs/PointCloud2",
        "sensor_msgs/JointState",
        "visualization_msgs/MarkerArray",
        "nav_msgs/Odometry",
        "sensor_msgs/NavSatFix",
        "diagnostic_msgs/DiagnosticArray",
        "rosgraph_msgs/Log",
        "std_msgs/Empty",
        "sensor_msgs/CameraInfo",
        "trajectory_msgs/JointTrajectory",
    ],
)
def test_random_round_trips(name: str) -> None:
    rand = RandomMessages(CODEC, seed=hash(name) & 0xFFFF)
    for _ in range(20):
        m = rand.message(name)
        wire = m.serialize()  # type: ignore[attr-defined]
        back = CODEC.decode(name, wire)
        assert back == m
        assert back.serialize() == wire


def test_truncated_and_hostile_input_raise_decode_error() -> None:
    wire = msg("sensor_msgs/JointState", name=["a", "b"], position=[1.0, 2.0]).serialize()  # type: ignore[attr-defined]
    for cut in range(len(wire)):
        with pytest.raises(DecodeError):
            CODEC.decode("sensor_msgs/JointState", wire[:cut])
    huge_count = bytes(16) + b"\xff\xff\xff\x7f"  # header, then a 2G-element name[]
    with pytest.raises(DecodeError):
        CODEC.decode("sensor_msgs/JointState", huge_count)
    with pytest.raises(DecodeError):
        CODEC.decode("std_msgs/Int8MultiArray", bytes(8) + b"\xff\xff\xff\xff")


def test_decode_from_memoryview() -> None:
    wire = msg("std_msgs/String", "abc").serialize()  # type: ignore[attr-defined]
    assert CODEC.decode("std_msgs/String", memoryview(bytearray(wire))).data == "abc"


def test_encode_errors_name_the_type() -> None:
    with pytest.raises(EncodeError, match="position_covariance: expected 9 elements, got 1"):
        msg("sensor_msgs/NavSatFix", position_covariance=[1.0]).serialize()  # type: ignore[attr-defined]
    with pytest.raises(EncodeError):
        msg("std_msgs/Int32", "x").serialize()  # type: ignore[attr-defined]


def test_defaults_and_constants() -> None:
    nav = msg("sensor_msgs/NavSatFix")
    assert nav.position_covariance == [0.0] * 9  # type: ignore[attr-defined]
    assert type(nav).COVARIANCE_TYPE_KNOWN == 3
    assert msg("sensor_msgs/Image").data == b""  # type: ignore[attr-defined]


@settings(max_examples=200, deadline=None)
@given(
    st.integers(-(2**31), 2**31 - 1),
    st.floats(allow_nan=False),
    st.text(),
    st.lists(st.integers(0, 2**64 - 1), max_size=5),
    st.binary(max_size=50),
)
def test_hypothesis_round_trip(i: int, f: float, s: str, u: list[int], b: bytes) -> None:
    store = TypeStore([BuiltinSource()]).with_definition(
        "t/T", "int32 i\nfloat64 f\nstring s\nuint64[] u\nuint8[] b\ntime t\nbool[2] flags\n"
    )
    codec = Codec.of(store)
    m = codec.message_class("t/T")(i, f, s, u, b, Time(5, 6), [True, False])
    back = codec.decode("t/T", m.serialize())
    assert (back.i, back.f, back.s, list(back.u), back.b) == (i, f, s, u, b)
    assert back.t == Time(5, 6) and list(back.flags) == [True, False]
