"""Parsing .msg/.srv text the way genmsg does."""

from __future__ import annotations

import pytest

from rostools.msgs.spec import DefinitionError, parse_msg, parse_srv, split_definition


def test_fields_constants_and_comments() -> None:
    spec = parse_msg(
        "# a comment\nint32 X=5 # five\nstring S=a # b\nHeader header\nPoint[] pts  # c\n"
        "uint8[16] id\n",
        "pkg/T",
    )
    assert [(c.type, c.name, c.value, c.text) for c in spec.constants] == [
        ("int32", "X", 5, "5"),
        ("string", "S", "a # b", "a # b"),  # everything after '=' for strings
    ]
    assert [(f.name, f.type) for f in spec.fields] == [
        ("header", "std_msgs/Header"),
        ("pts", "pkg/Point[]"),
        ("id", "uint8[16]"),
    ]
    assert spec.has_header
    assert spec.dependencies == ("std_msgs/Header", "pkg/Point")
    assert spec.fields[2].is_array and spec.fields[2].length == 16


@pytest.mark.parametrize(
    ("line", "value", "text"),
    [
        ("float64 X=1e-3", 0.001, "1e-3"),
        ("float64 X=1.50", 1.5, "1.50"),
        ("int32 X=+5", 5, "+5"),
        ('string S="hi"', '"hi"', '"hi"'),
        ("string S=", "", ""),
        ("bool B=True", True, "True"),
        ("bool B=0", False, "0"),
    ],
)
def test_constant_literals_keep_their_text(line: str, value: object, text: str) -> None:
    (c,) = parse_msg(line + "\n", "pkg/T").constants
    assert c.value == value
    assert c.text == text


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        ("int32\tx\n", "invalid declaration"),  # genmsg splits on spaces only
        ("int32 x y\n", "invalid declaration"),
        ("int8 X=0x10\n", "invalid constant value"),
        ("uint8 X=256\n", "out of bounds"),
        ("time T=1\n", "not a legal constant type"),
        ("int32 1x\n", "not a legal message field name"),
        ("int32 x\nint32 x\n", "duplicate field name"),
        ("int32[a] x\n", "not a legal message field type"),
    ],
)
def test_malformed_lines_name_the_problem(text: str, problem: str) -> None:
    with pytest.raises(DefinitionError, match=problem):
        parse_msg(text, "pkg/T")


def test_srv_splits_on_dashes() -> None:
    srv = parse_srv("int64 a\nint64 b\n---\nint64 sum\n", "pkg/AddTwoInts")
    assert srv.request.name == "pkg/AddTwoIntsRequest"
    assert [f.name for f in srv.request.fields] == ["a", "b"]
    assert [f.name for f in srv.response.fields] == ["sum"]
    assert srv.request.text == "int64 a\nint64 b\n"


def test_split_definition_inverts_full_text() -> None:
    full = (
        "Header header\nPoint p\n\n" + "=" * 80 + "\nMSG: std_msgs/Header\nuint32 seq\n"
        "time stamp\nstring frame_id\n\n" + "=" * 80 + "\nMSG: geometry_msgs/Point\nfloat64 x\n"
    )
    sections = split_definition(full, "geometry_msgs/PointStamped")
    assert list(sections) == [
        "geometry_msgs/PointStamped",
        "std_msgs/Header",
        "geometry_msgs/Point",
    ]
    assert sections["geometry_msgs/PointStamped"] == "Header header\nPoint p\n"
    assert sections["geometry_msgs/Point"] == "float64 x\n"
