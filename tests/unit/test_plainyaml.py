"""``plainyaml``: the YAML ``param get`` prints without PyYAML is PyYAML's, byte for byte."""

from __future__ import annotations

import xmlrpc.client
from typing import Any

import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from rostools.cli.param import paramyaml, plainyaml

TRICKY_STRINGS = [
    "", " ", " x", "x ", "a b", "a: b", "a:b", "#", "a #b", "a#b", "-", "- x", "-x", "--", "---",
    "...", ".", "./a", "/", "/a/b", "~", "~x", "yes", "Yes", "YES", "no", "No", "on", "OFF",
    "true", "False", "null", "Null", "NULL", "y", "n", "Y", "N", "1", "1.0", "-1", "+1", ".5",
    "1e3", "1.0e+3", "0x1F", "0o17", "0b1", "1_000", "1:20", "2001-12-14", ".inf", ".nan",
    "-.inf", "<<", "=", "é", "日本", "a\nb", "a\tb", "'", '"', "a'b", "!tag", "&a", "*a", "%",
    "@", "`", "?", "? x", "[a]", "{a}", "a,b", "|", ">", "a" * 200, "a " * 50, "_", "_a",
    "a.b-c/d_e", "x" * 122, "x" * 123, "ros", "talker_1", "\x7f", "\x85", "\u2028", "\ufeff",
]  # fmt: skip

TRICKY_VALUES: list[Any] = [
    0, 1, -1, 2**31 - 1, -(2**31), 10**30, True, False, 0.0, -0.0, 1.5, -2.25, 1e16, 1e-5,
    1.5e300, 3.141592653589793, 1e22, 123456789.123, float("inf"), float("-inf"), float("nan"),
    [], {}, [[]], [{}], {"a": []}, {"a": {}}, [1, [2, [3, []]]], [[1, 2], [3]],
    {"a": [1, 2], "b": {"c": [{"d": 1, "e": [True]}], "f": "g"}}, [{"a": 1, "b": [{"c": 2}]}],
    {"b": 1, "a": 2, "B": 3, "_": 4, "/x": 5}, {"yes": 1}, {"1": 2}, {"a b": 1}, {"x" * 127: 1},
    {"x" * 128: 1}, {"é": 1}, {"": 1}, {1: 2}, {"a": None}, None, (1, 2),
    xmlrpc.client.Binary(b"\x00\xff"), {"bin": xmlrpc.client.Binary(b"abc")},
    xmlrpc.client.DateTime("20260101T00:00:00"), {"a": [[[]], {}], "b": [[{"c": []}]]},
]  # fmt: skip


def same(value: Any, pretty: bool = False) -> None:
    """``plainyaml.dump`` prints what ``paramyaml.dump`` prints, or PyYAML's error."""
    try:
        expected = paramyaml.dump(value, pretty=pretty)
    except Exception as err:  # noqa: BLE001 - whatever PyYAML raises, plain must not print
        assert plainyaml.plain(value) is None, (value, err)
        return
    assert plainyaml.dump(value, pretty=pretty) == expected, value
    text = plainyaml.plain(value)
    assert text is None or text == expected, value


@pytest.mark.parametrize("text", TRICKY_STRINGS)
def test_strings(text: str) -> None:
    for value in (text, [text], {"k": text}, {"k": [text]}, [{"k": text}]):
        same(value)
        same(value, pretty=True)
    if "\n" not in text:
        same({text: 1})


@pytest.mark.parametrize("value", TRICKY_VALUES)
def test_values(value: Any) -> None:
    same(value)
    same([value, value] if isinstance(value, list | dict) else value)
    same({"k": value, "l": [value]})


def test_common_values_do_not_need_pyyaml() -> None:
    """The values most parameters hold are printed without PyYAML."""
    for value in (1, 2.5, True, "text", "/ns/name", [1.5, 2.5], {"d": [1.5, 2.5], "e": True}):
        assert plainyaml.plain(value) is not None, value


def test_an_object_met_twice_is_left_to_pyyaml() -> None:
    """PyYAML anchors a list met twice (``&id001``); plain must not print it without."""
    shared = [1, 2]
    assert plainyaml.plain({"a": shared, "b": shared}) is None
    same({"a": shared, "b": shared})


# Mostly names, which print plain, and now and then a word YAML reads as a boolean or a number.
words = st.from_regex(r"[a-zA-Z_/][a-z0-9_./-]{0,6}", fullmatch=True) | st.text("yesnoON1.-")
scalars = st.one_of(
    st.integers(-(2**40), 2**40),
    st.booleans(),
    st.floats(allow_nan=False, allow_infinity=False),
    words,
    words,
    st.sampled_from(TRICKY_STRINGS),
    st.text(st.characters(codec="utf-8"), max_size=8),
)
keys = st.one_of(words, words, words, words, st.sampled_from(TRICKY_STRINGS))
values = st.recursive(
    scalars,
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(keys, inner, max_size=4),
    max_leaves=12,
)
# Nested layouts of values that print plain: the block layout itself, at every depth.
names = st.from_regex(r"[a-zA-Z_/][a-z0-9_./-]{0,6}", fullmatch=True)
layouts = st.recursive(
    st.integers() | st.booleans() | st.floats(allow_nan=False, allow_infinity=False) | names,
    lambda inner: st.lists(inner, max_size=3) | st.dictionaries(names, inner, max_size=3),
    max_leaves=16,
).filter(lambda v: isinstance(v, list | dict))


@settings(
    max_examples=150, derandomize=True, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)
@given(layouts | values)
def test_random_values(value: Any) -> None:
    same(value)
