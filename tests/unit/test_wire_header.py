"""Connection header fields (``wire/header.py``) at their edges.

The rules are rospy's (``rosgraph.network.decode_ros_handshake_header``: a zero-length field
is refused, a field is split at its first ``=``, the key is stripped and the value is not)
and roscpp's (``Header::parse``: a field over 1,000,000 bytes is refused); wiki.ros.org's
ROS/Connection Header.
"""

from __future__ import annotations

import struct

import pytest

from rostools.wire.header import (
    MAX_FIELD_LENGTH,
    HeaderError,
    decode_fields,
    encode_fields,
    encode_header,
    split_fields,
)


def field(raw: bytes) -> bytes:
    return struct.pack("<I", len(raw)) + raw


def test_a_one_byte_field_is_an_empty_key_and_value() -> None:
    assert split_fields(field(b"=")) == {"": b""}
    assert split_fields(field(b"=") + field(b"a=1")) == {"": b"", "a": b"1"}


def test_keys_are_stripped_values_are_not() -> None:
    assert split_fields(field(b" type =  x ")) == {"type": b"  x "}


def test_a_zero_length_field_is_refused() -> None:
    with pytest.raises(HeaderError, match=r"^empty header field$"):
        split_fields(field(b"a=1") + field(b""))


@pytest.mark.parametrize("tail", [b"\x01", b"\x01\x00", b"\x01\x00\x00"])
def test_a_cut_field_length_is_refused(tail: bytes) -> None:
    with pytest.raises(HeaderError, match=r"^truncated field length$"):
        split_fields(field(b"a=1") + tail)


def test_a_field_that_ends_exactly_at_the_end_is_whole() -> None:
    data = field(b"a=1") + field(b"b=22")
    assert split_fields(data) == {"a": b"1", "b": b"22"}
    with pytest.raises(HeaderError, match=r"^header field of 4 bytes does not fit$"):
        split_fields(data[:-1])


def test_a_field_longer_than_roscpps_limit_is_refused() -> None:
    at_limit = b"k=" + b"v" * (MAX_FIELD_LENGTH - 2)
    assert split_fields(field(at_limit)) == {"k": at_limit[2:]}
    over = at_limit + b"v"
    with pytest.raises(HeaderError, match=f"^header field of {MAX_FIELD_LENGTH + 1} bytes"):
        split_fields(field(over))
    # refused for its length alone, even when the bytes are all there
    with pytest.raises(HeaderError, match="does not fit"):
        split_fields(field(over) + b"\0" * 16)


def test_a_field_without_equals_names_its_start() -> None:
    with pytest.raises(HeaderError) as caught:
        split_fields(field(b"x" * 100))
    assert str(caught.value) == "header field without '=': " + repr(b"x" * 40)


def test_text_that_is_not_utf8_is_replaced_not_refused() -> None:
    fields = decode_fields(field(b"k\xff=v\xfe"))
    assert fields == {"k\ufffd": "v\ufffd"}


def test_binary_values_are_written_as_they_are() -> None:
    # bag record headers carry binary values (wiki.ros.org/Bags/Format/2.0): u32 length, key=value
    assert encode_fields({"op": b"\x02", "a": "1"}) == b"\x03\x00\x00\x00a=1\x04\x00\x00\x00op=\x02"
    assert encode_header({"op": b"\x02"}) == b"\x08\x00\x00\x00\x04\x00\x00\x00op=\x02"
