"""Messages in rosbridge_server's JSON: its rules, generated per type (issue 35's encoding).

rosbridge 0.11.17 writes ``json.dumps(extract_values(msg))``: ``uint8[]`` and ``char[]`` as
standard base64, strings escaped to ASCII (``ensure_ascii``), NaN and infinities as the
``NaN``/``Infinity`` tokens JavaScript's parsers take, fields in definition order.
"""

from __future__ import annotations

import base64
import json

import pytest

from rostools._api.messages import message, store
from rostools.msgs.codec import Codec
from rostools.msgs.codegen import element
from rostools.msgs.plain import to_rosbridge_json


def encode(type_name: str, values: dict[str, object]) -> str:
    return to_rosbridge_json(Codec.of(store()), element(type_name))(message(type_name, values))


def test_bytes_are_base64_and_other_integer_arrays_are_lists() -> None:
    text = encode("sensor_msgs/Image", {"width": 2, "data": b"\x00\xff\x10"})
    assert json.loads(text)["data"] == base64.b64encode(b"\x00\xff\x10").decode()
    assert json.loads(encode("std_msgs/Int16MultiArray", {"data": [1, -2]}))["data"] == [1, -2]
    assert json.loads(encode("std_msgs/Char", {"data": 65})) == {"data": 65}


def test_strings_are_ascii_and_floats_are_pythons_json() -> None:
    text = encode("std_msgs/String", {"data": 'é "q"\n'})
    assert text == '{"data":"\\u00e9 \\"q\\"\\n"}'
    floats = encode("std_msgs/Float64MultiArray", {"data": [1.5, float("nan"), float("-inf")]})
    assert floats.endswith('"data":[1.5,NaN,-Infinity]}')
    assert json.loads(encode("std_msgs/Float32", {"data": 0.1}))["data"] == pytest.approx(0.1)


def test_nested_messages_times_and_arrays_of_messages_keep_their_order() -> None:
    cloud = json.loads(
        encode("sensor_msgs/PointCloud2", {"fields": [{"name": "x", "datatype": 7, "count": 1}]})
    )
    assert list(cloud) == [
        "header", "height", "width", "fields", "is_bigendian", "point_step", "row_step",
        "data", "is_dense",
    ]  # fmt: skip
    assert cloud["header"] == {"seq": 0, "stamp": {"secs": 0, "nsecs": 0}, "frame_id": ""}
    assert cloud["fields"] == [{"name": "x", "offset": 0, "datatype": 7, "count": 1}]
    assert (cloud["data"], cloud["is_dense"]) == ("", False)
