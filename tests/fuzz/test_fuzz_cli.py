"""Fuzz the values users type: YAML for ``topic pub``, ``param set`` and ``param load``.

The master is unreachable (the discard port), so a value that parses ends in exit 4 (or 0,
when there is nothing to send); one that does not, in exit 2. The invariant: one of those,
in one line, with no traceback.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from hypothesis import given, seed, strategies as st

from tests.fuzz.conftest import FUZZ, SEED
from tests.fuzz.test_fuzz_bags import _run
from tests.unit.test_yamlio import BOMB

SPECIAL = st.sampled_from(
    [
        "[" * 5000 + "]" * 5000, "1" * 5000, "nan", ".nan", "-.inf", "1e400", "0x" + "f" * 40,
        "&a [*a]", BOMB, "{a: 1", "!!binary x", "!!python/object:os.system x", "deg(", "rad(1/0)",
        "- - - -", "\x00", "\ud800", "{data: [1, 2, 3]}", "{x: 1, y: 2, z: 3}", "data: hello",
        "[" + ", ".join(["1.5"] * 10_000) + "]", "'''", "? a : b", "*a",
    ]
)  # fmt: skip
JSONISH = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=20),
    lambda inner: (
        st.lists(inner, max_size=5) | st.dictionaries(st.text(max_size=6), inner, max_size=5)
    ),
    max_leaves=30,
).map(lambda v: json.dumps(v))
VALUES = SPECIAL | JSONISH | st.text(max_size=60)
TYPES = st.sampled_from(
    ["std_msgs/String", "std_msgs/Int8", "geometry_msgs/Pose", "sensor_msgs/JointState"]
)


@pytest.fixture(autouse=True)
def no_master(monkeypatch: pytest.MonkeyPatch) -> None:
    """Every command here asks a master that is not there (exit 4 once the input is good)."""
    monkeypatch.setenv("ROS_MASTER_URI", "http://127.0.0.1:9")
    monkeypatch.setenv("ROSTOOLS_MASTER_TIMEOUT", "1")


def _clean(code: int, err: str, args: list[str]) -> None:
    if code == 0:  # nothing to send (an empty mapping sets nothing), so no master asked
        assert not err, (args[:3], err)
        return
    # A value that starts with "-" may spell an option: "-t0" is --textfile 0, not found.
    assert code in (2, 4) or (code == 3 and args[-1].startswith("-")), (args[:3], code, err)
    assert "Traceback" not in err and "internal error" not in err, (args[:3], err)
    assert len(err.strip().splitlines()) == 1, (args[:3], err)


@seed(SEED)
@FUZZ
@given(TYPES, VALUES)
def test_pub_values(type_name: str, value: str) -> None:
    args = ["topic", "pub", "-1", "/fuzzed", type_name, value]
    _clean(*_run(*args), args)


@seed(SEED)
@FUZZ
@given(VALUES)
def test_param_set_values(value: str) -> None:
    args = ["param", "set", "/fuzzed", value]
    _clean(*_run(*args), args)


@seed(SEED)
@FUZZ
@given(VALUES)
def test_param_load_files(tmp_path_factory: pytest.TempPathFactory, value: str) -> None:
    path = tmp_path_factory.getbasetemp() / "fuzzed.yaml"
    Path(path).write_text(value, errors="surrogatepass")  # lone surrogates: bad UTF-8
    args = ["param", "load", str(path)]
    _clean(*_run(*args), args)
