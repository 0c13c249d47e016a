"""The ROS 1 -> CDR converters (``bag/formats/ros2cdr.py``) where a ROS 2 type differs from its
ROS 1 one: each case against rosbags-convert's own message migration, byte for byte."""

from __future__ import annotations

import struct
from typing import Any

import pytest

from rostools.bag.formats.ros2cdr import ConversionError, Converters, ReorderedFieldsError


def _stores(src: dict[str, str], dst: dict[str, str]) -> tuple[Any, Any]:
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    stores = []
    for texts in (src, dst):
        store = get_typestore(Stores.EMPTY)
        for name, text in texts.items():
            store.register(get_types_from_msg(text, name))
        stores.append(store)
    return stores[0], stores[1]


def _both(src: dict[str, str], dst: dict[str, str], name: str, data: bytes) -> tuple[bytes, bytes]:
    """(ours, rosbags-convert's) CDR of ROS 1 ``data`` of ``name``."""
    from rosbags.convert.converter import generate_message_converter

    s, d = _stores(src, dst)
    conv = Converters(lambda n: s.fielddefs[n][1], lambda n: d.fielddefs[n][1])
    ours = bytes(conv.converter(name, name)(data))
    theirs = generate_message_converter(s, d, name, name, {}, src_is2=False, dst_is2=True)
    return ours, bytes(theirs(data))


def _string(text: str) -> bytes:
    return struct.pack("<I", len(text)) + text.encode()


CASES = {
    "a fixed array cut, a new string, a number's type changed": (
        "uint8 a\nfloat64[] values\nfloat32 x\n",
        "uint8 a\nstring name\nfloat64[3] values\nfloat64 x\n",
        struct.pack("<BI5df", 7, 5, *range(5), 1.5),
    ),
    "a fixed array padded": (
        "float64[] values\n",
        "float64[3] values\n",
        struct.pack("<I1d", 1, 2.5),
    ),
    "a bounded sequence cut to its bound": (
        "uint16[] v\nuint8 tail\n",
        "uint16[<=2] v\nuint8 tail\n",
        struct.pack("<I4HB", 4, 1, 2, 3, 4, 9),
    ),
    "a string where ROS 2 has a number: its default": (
        "string x\nint32 y\n",
        "int32 x\nint32 y\n",
        _string("hello") + struct.pack("<i", -5),
    ),
    "a removed field skipped, arrays of strings kept": (
        "string[] gone\nstring[] names\nint64 z\n",
        "string[] names\nint64 z\n",
        struct.pack("<I", 2)
        + _string("a")
        + _string("bc")
        + struct.pack("<I", 1)
        + _string("def")
        + struct.pack("<q", -1),
    ),
    "an empty sequence is not aligned to its element": (  # its count ends at 4 mod 8
        "uint8 a\nuint32 n\nfloat64[] v\nuint8 b\nint16 c\n",
        "uint8 a\nuint32 n\nfloat64[] v\nuint8 b\nint16 c\nfloat64 added\n",
        struct.pack("<BIIBh", 1, 5, 0, 2, 3),
    ),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_a_changed_type_converts_as_rosbags_convert_migrates_it(case: str) -> None:
    src, dst, data = CASES[case]
    ours, theirs = _both({"p/msg/T": src}, {"p/msg/T": dst}, "p/msg/T", data)
    assert ours == theirs


def test_nested_messages_in_sequences_gain_their_new_fields() -> None:
    src = {"p/msg/Inner": "uint8 a\nstring s\n", "p/msg/Outer": "p/Inner[] items\nuint32 n\n"}
    dst = {"p/msg/Inner": "uint8 a\nstring s\nfloat64 b\n", "p/msg/Outer": src["p/msg/Outer"]}
    items = struct.pack("<B", 1) + _string("xy") + struct.pack("<B", 2) + _string("")
    data = struct.pack("<I", 2) + items + struct.pack("<I", 42)
    ours, theirs = _both(src, dst, "p/msg/Outer", data)
    assert ours == theirs


def test_reordered_fields_are_refused_by_name_and_bad_bytes_raise_one_error() -> None:
    with pytest.raises(ReorderedFieldsError, match="p/msg/T"):
        _both(
            {"p/msg/T": "int32 a\nfloat64 b\n"}, {"p/msg/T": "float64 b\nint32 c\n"}, "p/msg/T", b""
        )
    s, d = _stores({"p/msg/T": "uint32 a\nstring s\n"}, {"p/msg/T": "uint32 a\nstring s\n"})
    convert = Converters(lambda n: s.fielddefs[n][1], lambda n: d.fielddefs[n][1]).converter(
        "p/msg/T", "p/msg/T"
    )
    with pytest.raises(ConversionError, match="shorter"):
        convert(b"\x01\x00")
    with pytest.raises(ConversionError, match="shorter"):
        convert(struct.pack("<II", 1, 99) + b"ab")  # a string longer than the message
    with pytest.raises(ConversionError, match="2 bytes more"):
        convert(struct.pack("<II", 1, 0) + b"zz")
