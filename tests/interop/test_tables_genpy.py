"""Bags as Arrow tables against real genpy: every value of a synthetic bag (types only the bag
defines: nested arrays of messages, empty arrays, ``uint8[]`` and ``char[]``, constants, time
at 0 and the largest secs, strings that are not UTF-8, NaN), read from ``.bag`` and MCAP."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest

from tests.support.env import needs_ros1
from tests.support.tables import first_difference, genpy_view, ours, write_synthetic_bag

pytestmark = needs_ros1
pytest.importorskip("pyarrow", reason="the arrow extra (in the test extra)")


@pytest.fixture(scope="module")
def genpy_and_files(tmp_path_factory: pytest.TempPathFactory) -> tuple[Any, Path, Path]:
    folder = tmp_path_factory.mktemp("tables")
    bag = write_synthetic_bag(folder / "every.bag")
    mcap = write_synthetic_bag(folder / "every.mcap")
    return genpy_view([bag])[str(bag)], bag, mcap


@pytest.mark.parametrize("kind", ["bag", "mcap"])
def test_every_value_is_genpys(kind: str, genpy_and_files: tuple[Any, Path, Path]) -> None:
    theirs, bag, mcap = genpy_and_files
    mine = ours([bag if kind == "bag" else mcap], batch_rows=2)  # batches end mid-table
    assert sorted(mine) == sorted(theirs) and len(theirs) == 2
    for key, rows in theirs.items():
        assert len(mine[key]) == len(rows) == 3
        for i, (a, b) in enumerate(zip(mine[key], rows, strict=True)):
            assert first_difference(list(a), list(b), f"{key} row {i}") is None
