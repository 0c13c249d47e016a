"""Big types in parts: what the codec and the formatters write for a type over ``PART_FIELDS``.

A type of more fields than ``PART_FIELDS`` (nested types' fields counted) is done by several
generated functions, and its ``__init__`` by a loop: compiled whole, a type of 100,000 fields
took 780 MB (issue 32). Here a codec whose ``part_fields`` is tiny does ordinary types in
parts, and everything it writes and reads must be what the ordinary codec does.
"""

from __future__ import annotations

from typing import Any

import pytest

from rostools.msgs import plain, text
from rostools.msgs.codec import Codec
from rostools.msgs.message import Time
from rostools.msgs.store import BuiltinSource, TypeStore
from tests.support.randmsg import RandomMessages

WHOLE = Codec(TypeStore([BuiltinSource()]))
TYPES = [
    "sensor_msgs/CameraInfo",  # fixed arrays in a struct run, nested Header and RegionOfInterest
    "nav_msgs/Odometry",  # nested twice, a fixed float64[36]
    "visualization_msgs/Marker",  # arrays of messages, times, strings, colours
    "diagnostic_msgs/DiagnosticStatus",  # an array of messages of strings
    "sensor_msgs/PointCloud2",  # uint8[] and bool
    "std_msgs/Empty",
]


def in_parts(size: int) -> Codec:
    """A codec over the same types whose functions each do at most ``size`` fields."""
    codec = Codec(TypeStore([BuiltinSource()]))
    codec.part_fields = size
    return codec


def wire(codec: Codec, name: str, msg: Any) -> bytes:
    pieces: list[Any] = []
    codec.encoder(name)(msg, pieces.append)
    return b"".join(pieces)


@pytest.mark.parametrize("size", [1, 2, 3])
@pytest.mark.parametrize("name", TYPES)
def test_parts_write_and_read_what_one_function_does(name: str, size: int) -> None:
    parts = in_parts(size)
    assert name == "std_msgs/Empty" or not parts.inline(name)
    rand = RandomMessages(WHOLE, seed=size)
    value_type = text.message_type(name)
    for _ in range(10):
        msg = rand.message(name)
        data = msg.serialize()  # type: ignore[attr-defined]
        assert wire(parts, name, msg) == data
        back = parts.decode(name, data)
        assert wire(WHOLE, name, back) == data
        for codec_of, form in [
            (text.formatter, lambda f, m: f(m)),
            (plain.to_json, lambda f, m: f(m)),
            (plain.to_plain, lambda f, m: f(m)),
        ]:
            assert form(codec_of(parts, value_type), back) == form(codec_of(WHOLE, value_type), msg)
        options = plain.CsvOptions()
        row = plain.csv_row(parts, value_type, options)(back)
        assert row == plain.csv_row(WHOLE, value_type, options)(msg)


def test_the_init_of_a_type_in_parts_takes_and_refuses_what_the_generated_one_does() -> None:
    name = "sensor_msgs/NavSatFix"  # a Header, numbers, a fixed array, a constant-bearing type
    parts, whole = in_parts(2).message_class(name), WHOLE.message_class(name)
    assert wire(in_parts(2), name, parts()) == whole().serialize()  # type: ignore[attr-defined]
    header = WHOLE.message_class("std_msgs/Header")(3, Time(1, 2), "gps")
    status = WHOLE.message_class("sensor_msgs/NavSatStatus")(1, 2)
    args = (header, status, 1.5)
    kwargs = {"altitude": 7.0, "position_covariance_type": 2}
    expected = whole(*args, **kwargs).serialize()  # type: ignore[attr-defined]
    assert wire(WHOLE, name, parts(*args, **kwargs)) == expected
    assert parts().position_covariance is not parts().position_covariance  # each its own
    for bad_args, bad_kwargs in [((0,) * 9, {}), ((), {"nope": 1}), ((1,), {"header": 1})]:
        with pytest.raises(TypeError) as ours:
            parts(*bad_args, **bad_kwargs)
        with pytest.raises(TypeError) as generated:
            whole(*bad_args, **bad_kwargs)
        assert str(ours.value) == str(generated.value)
