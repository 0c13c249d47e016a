"""YAML from users: the same values as PyYAML, fast, bounded, one line when it is wrong."""

from __future__ import annotations

import json
import time
from typing import Any

import pytest
import yaml
from hypothesis import given, settings, strategies as st

from rostools import yamlio
from rostools.errors import UsageError

#: Nine levels of nine aliases: 300 bytes that expand to 387 million values.
BOMB = "a: &a [x, x, x, x, x, x, x, x, x]\n" + "".join(
    f"{chr(98 + i)}: &{chr(98 + i)} [{', '.join(['*' + chr(97 + i)] * 9)}]\n" for i in range(8)
)


def test_an_alias_bomb_is_refused_at_once() -> None:
    # the defect: param load of this file ran past 30 s until killed
    began = time.monotonic()
    with pytest.raises(UsageError, match=r"bad YAML in bomb.yaml: it expands to more than"):
        yamlio.load_all(BOMB, "bomb.yaml")
    assert time.monotonic() - began < 10  # expanding it would take hours


@pytest.mark.parametrize(
    ("text", "problem"),
    [
        ("[" * 10_000 + "]" * 10_000, "nested deeper than 100 levels"),  # was a RecursionError
        ("a:\n" + "".join("  " * i + "b:\n" for i in range(1, 150)) + "  " * 150 + "c", "nested"),
        ("1" * 10_000, "an integer too long to read"),  # was Python's int-conversion ValueError
        ("&a [*a]", "a value that contains itself"),
        ("{a: 1\nb: [", "(line"),
    ],
)
def test_bad_yaml_is_one_line(text: str, problem: str) -> None:
    with pytest.raises(UsageError) as caught:
        yamlio.load_all(text, "the input")
    message = str(caught.value)
    assert message.startswith("bad YAML in the input: ") and problem in message
    assert "\n" not in message


def test_a_million_numbers_load_without_pyyaml(monkeypatch: pytest.MonkeyPatch) -> None:
    # the defect: pub -f with a million-element array was still running after 20 s in PyYAML;
    # a flow-style document is read as JSON (not a timing: that was flaky on a loaded machine)
    def no_pyyaml(*_: object, **__: object) -> None:
        raise AssertionError("PyYAML read a JSON document")

    monkeypatch.setattr(yamlio.yaml, "load_all", no_pyyaml)
    text = "[" + ", ".join(str(i) for i in range(1_000_000)) + "]"
    assert yamlio.load(text, "big")[-1] == 999_999


@pytest.mark.parametrize(
    "text", ['[1, 1.5, 1e3, 1.0e+3, 2E-2, -0, true, null, "x", NaN]', '{"a": [1.0], "b": 1e5}']
)
def test_the_json_path_reads_numbers_as_yaml_does(text: str) -> None:
    assert yamlio.load(text, "t") == yaml.safe_load(text)


JSON = st.recursive(
    st.none()
    | st.booleans()
    | st.integers()
    | st.floats(allow_nan=False, allow_infinity=False)
    | st.text(st.characters(blacklist_categories=("Cs", "Cc"))),
    lambda inner: (
        st.lists(inner, max_size=4)
        | st.dictionaries(
            st.text(st.characters(blacklist_categories=("Cs", "Cc"))), inner, max_size=4
        )
    ),
    max_leaves=20,
)


@settings(max_examples=200, deadline=None, derandomize=True)
@given(JSON)
def test_any_json_document_reads_as_pyyaml_reads_it(value: Any) -> None:
    text = json.dumps(value, ensure_ascii=False)
    assert yamlio.load(text, "t") == yaml.safe_load(text)
