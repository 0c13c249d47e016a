"""``TransformBuffer``: tf2 ``BufferCore``'s semantics, checked by hand (the parity with tf2
itself is ``tests/interop/test_tf_buffer_parity.py``)."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings, strategies as st

from rostools.tf.buffer import (
    ConnectivityError,
    ExtrapolationError,
    FrameNotFoundError,
    InvalidFrameError,
    LoopError,
    TransformBuffer,
)
from rostools.tf.records import Stamped

S = 1_000_000_000
ID = (0.0, 0.0, 0.0, 1.0)


def T(parent: str, child: str, stamp: int, xyz=(0.0, 0.0, 0.0), q=ID) -> Stamped:
    return Stamped(parent, child, stamp, xyz, q)


def yaw(angle: float) -> tuple[float, float, float, float]:
    return (0.0, 0.0, math.sin(angle / 2), math.cos(angle / 2))


def test_translation_interpolates_and_rotation_slerps_between_neighbours() -> None:
    b = TransformBuffer()
    b.set_transform(T("a", "b", 10 * S, (0.0, 0.0, 0.0), yaw(0.0)))
    b.set_transform(T("a", "b", 12 * S, (2.0, 4.0, 0.0), yaw(math.pi / 2)))
    r = b.lookup("a", "b", 11 * S)
    assert r.translation == pytest.approx((1.0, 2.0, 0.0))
    assert r.rotation == pytest.approx(yaw(math.pi / 4))
    assert (r.parent, r.child, r.stamp_ns) == ("a", "b", 11 * S)


def test_a_chain_composes_and_the_reverse_inverts() -> None:
    b = TransformBuffer()
    b.set_transform(T("world", "base", S, (1.0, 0.0, 0.0), yaw(math.pi / 2)))
    b.set_transform(T("base", "cam", S, (1.0, 0.0, 0.0)))
    # cam is 1 m ahead of base, base is turned 90 degrees: cam sits at (1, 1) in world
    assert b.lookup("world", "cam", S).translation == pytest.approx((1.0, 1.0, 0.0))
    back = b.lookup("cam", "world", S)
    assert back.translation == pytest.approx((-1.0, 1.0, 0.0))


def test_time_zero_is_the_latest_common_time_of_the_path() -> None:
    b = TransformBuffer()
    for t in (1, 2, 3):
        b.set_transform(T("w", "a", t * S))
    for t in (1, 2):
        b.set_transform(T("a", "b", t * S))
    assert b.lookup("w", "b", 0).stamp_ns == 2 * S
    assert b.latest_common_time("w", "b") == 2 * S


def test_static_transforms_hold_at_every_time_and_never_expire() -> None:
    b = TransformBuffer(cache_time_ns=S)
    b.set_transform(T("base", "laser", 0, (0.5, 0.0, 0.0)), static=True)
    b.set_transform(T("odom", "base", 100 * S))
    assert b.lookup("odom", "laser", 100 * S).translation == pytest.approx((0.5, 0.0, 0.0))
    assert b.lookup("base", "laser", 0).stamp_ns == 0  # all static: tf2's time 0
    assert b.lookup("base", "laser", 5 * S).stamp_ns == 5 * S


def test_the_cache_keeps_its_time_and_refuses_older_data_as_tf2() -> None:
    b = TransformBuffer(cache_time_ns=2 * S)
    for t in range(10):
        assert b.set_transform(T("a", "b", t * S)) is None
    refused = b.set_transform(T("a", "b", 5 * S))
    assert refused is not None and refused.code == "TF_OLD_DATA"
    with pytest.raises(ExtrapolationError, match="into the past"):
        b.lookup("a", "b", 6 * S)
    assert b.lookup("a", "b", 7 * S).stamp_ns == 7 * S


def test_a_repeated_stamp_keeps_the_first_as_tf2() -> None:
    b = TransformBuffer()
    b.set_transform(T("a", "b", S, (1.0, 0.0, 0.0)))
    refused = b.set_transform(T("a", "b", S, (5.0, 0.0, 0.0)))
    assert refused is not None and refused.code == "TF_REPEATED_DATA"
    assert b.lookup("a", "b", S).translation[0] == 1.0


@pytest.mark.parametrize(
    ("t", "code"),
    [
        (T("a", "a", S), "TF_SELF_TRANSFORM"),
        (T("", "a", S), "TF_NO_FRAME_ID"),
        (T("a", "", S), "TF_NO_CHILD_FRAME_ID"),
        (T("a", "b", S, (math.nan, 0.0, 0.0)), "TF_NAN_INPUT"),
        (T("a", "b", S, q=(0.0, 0.0, 0.0, 2.0)), "TF_DENORMALIZED_QUATERNION"),
    ],
)
def test_what_tf2_refuses_is_refused(t: Stamped, code: str) -> None:
    b = TransformBuffer()
    refused = b.set_transform(t, "node")
    assert refused is not None and refused.code == code and '"node"' in refused.message
    assert b.frames() == []


def test_errors_say_what_tf2_says() -> None:
    b = TransformBuffer()
    b.set_transform(T("a", "b", 10 * S))
    b.set_transform(T("a", "b", 12 * S))
    b.set_transform(T("z", "y", 10 * S))
    with pytest.raises(ExtrapolationError) as future:
        b.lookup("a", "b", 13 * S)
    assert str(future.value) == (
        "Lookup would require extrapolation 1.000000000s into the future.  Requested time"
        " 13.000000000 but the latest data is at time 12.000000000, when looking up transform"
        " from frame [b] to frame [a]"
    )
    with pytest.raises(ConnectivityError, match="not part of the same tree"):
        b.lookup("a", "y", 0)
    with pytest.raises(FrameNotFoundError, match='"q" passed to lookupTransform argument source'):
        b.lookup("a", "q", 0)
    with pytest.raises(InvalidFrameError, match="cannot start with a '/'"):
        b.lookup("/a", "b", 0)
    assert FrameNotFoundError("x").exit_code == 3


def test_a_loop_is_an_error_not_a_hang() -> None:
    b = TransformBuffer()
    b.set_transform(T("k", "l", S))
    b.set_transform(T("m", "k", S))
    b.set_transform(T("k", "m", S))
    with pytest.raises(LoopError, match="contains a loop"):
        b.lookup("l", "m", S)


def test_a_leading_slash_is_stripped_on_the_way_in() -> None:
    b = TransformBuffer()
    b.set_transform(T("/map", "/odom", S, (1.0, 0.0, 0.0)))
    assert b.frames() == ["odom", "map"]
    assert b.lookup("map", "odom", 0).translation[0] == 1.0


finite = st.floats(-100, 100)
quats = st.tuples(*[st.floats(-1, 1)] * 4).filter(lambda q: sum(v * v for v in q) > 0.1)


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(st.tuples(finite, finite, finite), quats), min_size=1, max_size=5))
def test_there_and_back_is_the_identity(chain: list) -> None:
    b = TransformBuffer()
    for i, (xyz, q) in enumerate(chain):
        n = math.sqrt(sum(v * v for v in q))
        b.set_transform(T(f"f{i}", f"f{i + 1}", S, xyz, tuple(v / n for v in q)))
    end = f"f{len(chain)}"
    there, back = b.lookup("f0", end, S), b.lookup(end, "f0", S)
    b2 = TransformBuffer()
    b2.set_transform(T("x", "y", S, there.translation, there.rotation))
    b2.set_transform(T("y", "z", S, back.translation, back.rotation))
    r = b2.lookup("x", "z", S)
    assert r.translation == pytest.approx((0.0, 0.0, 0.0), abs=1e-6)
    assert abs(r.rotation[3]) == pytest.approx(1.0, abs=1e-9)
