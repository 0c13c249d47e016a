"""One options record for the bag tools: filter, convert, (de)compress, merge and split."""

from __future__ import annotations

import dataclasses
import inspect
from collections.abc import Callable
from pathlib import Path
from typing import Any

import pytest

from rostools.bag.formats.model import BagUsageError
from rostools.bag.tools import ops
from rostools.bag.tools.merge import merge
from rostools.bag.tools.options import CopyOptions
from rostools.bag.tools.split import Cut, split
from tests.support.bagdata import STEP_NS, read_stream, write_sample

TOOLS: list[Callable[..., Any]] = [
    ops.filter_bag, ops.convert, ops.compress, ops.decompress, merge, split
]  # fmt: skip


@pytest.mark.parametrize("tool", TOOLS, ids=lambda f: f.__name__)
def test_every_tool_takes_the_record_and_none_of_its_fields(tool: Callable[..., Any]) -> None:
    parameters = inspect.signature(tool).parameters
    assert parameters["options"].annotation == "CopyOptions"
    shared = {f.name for f in dataclasses.fields(CopyOptions)}
    assert not shared & set(parameters), shared & set(parameters)


def test_the_record_is_frozen() -> None:
    with pytest.raises(dataclasses.FrozenInstanceError):
        CopyOptions().overwrite = True  # type: ignore[misc]


def test_split_takes_what_the_options_select(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "s.bag", 400)
    lo, hi = 100 * STEP_NS, 300 * STEP_NS
    options = CopyOptions(topics=["/chatter"], start=lo, end=hi, expression="t.nsecs >= 0")
    report = split(sample.path, tmp_path / "z.bag", Cut(count=20), options)
    written = [m for part in report.parts for m in read_stream(part.path)]
    assert written == [m for m in sample.stream if m[0] == "/chatter" and lo <= m[2] <= hi]
    assert written and all(p.messages <= 20 for p in report.parts)


def test_decompress_refuses_a_compression(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "s.bag", 10)
    with pytest.raises(BagUsageError, match="decompress writes no compression, not lz4"):
        ops.decompress(sample.path, tmp_path / "d.bag", CopyOptions(compression="lz4"))
    assert not (tmp_path / "d.bag").exists()


@pytest.mark.parametrize(("name", "default"), [("x.bag", "bz2"), ("x.mcap", "zstd")])
def test_compress_defaults_to_the_formats_compression(
    tmp_path: Path, name: str, default: str
) -> None:
    sample = write_sample(tmp_path / name, 50, compression="none")
    report = ops.compress(sample.path, tmp_path / ("c" + Path(name).suffix))
    assert report.compression == default
    assert read_stream(report.output) == sample.stream
