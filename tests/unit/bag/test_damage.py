"""Damaged files: whatever the damage, readers raise our errors, never a raw exception."""

from __future__ import annotations

import random
from pathlib import Path

import pytest

from rostools.bag.access import open_bag
from rostools.bag.recover import recover
from rostools.errors import RostoolsError
from tests.support.bagdata import write_sample

CASES = [
    ("x.bag", "none"),
    ("x.bag", "bz2"),
    ("x.bag", "lz4"),
    ("x.mcap", "zstd"),
    ("x.mcap", "lz4"),
    ("x.mcap", "none"),
]


def read_everything(path: Path) -> None:
    with open_bag(path) as reader:
        reader.info()
        for _ in reader.messages():
            pass
        for _ in reader.times():
            pass


@pytest.mark.parametrize(("name", "compression"), CASES)
def test_random_damage_gives_our_errors(tmp_path: Path, name: str, compression: str) -> None:
    sample = write_sample(tmp_path / name, 300, compression=compression, chunk_size=3000)
    raw = sample.path.read_bytes()
    rng = random.Random(f"{name}{compression}")
    bad = tmp_path / ("bad" + Path(name).suffix)
    for _ in range(60):
        damaged = bytearray(raw)
        for _ in range(rng.randint(1, 4)):
            at = rng.randrange(len(raw))
            damaged[at : at + rng.randint(1, 16)] = rng.randbytes(rng.randint(1, 16))
        if rng.random() < 0.3:
            damaged = damaged[: rng.randrange(len(damaged))]
        bad.write_bytes(bytes(damaged))
        for action in (
            read_everything,
            lambda p: recover(p, tmp_path / "out" / p.name, overwrite=True),
        ):
            (tmp_path / "out").mkdir(exist_ok=True)
            try:
                action(bad)
            except RostoolsError as err:
                assert "\n" not in str(err)
