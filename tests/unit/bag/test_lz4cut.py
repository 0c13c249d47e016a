"""Salvaging cut-short LZ4 frames: every sequence before the cut, never a wrong byte."""

from __future__ import annotations

import random

import lz4.frame
import pytest
from hypothesis import given, settings, strategies as st

from rostools.bag.formats import lz4cut
from rostools.bag.formats.rosbag1_format import lz4_compress


def compressible(n: int, seed: int = 1) -> bytes:
    """Message-like bytes: repeated words and zero runs, so blocks hold many long matches."""
    rng = random.Random(seed)
    words = [rng.randbytes(rng.randint(1, 12)) for _ in range(200)]
    out = bytearray()
    while len(out) < n:
        out += rng.choice(words) + b"\0" * rng.randint(0, 40)
    return bytes(out[:n])


FRAMES = {
    "roslz4 (one 1 MB independent block)": lz4_compress,
    "linked 64 KB blocks": lambda d: lz4.frame.compress(
        d, block_size=lz4.frame.BLOCKSIZE_MAX64KB, block_linked=True, store_size=True
    ),
    "lz4.frame defaults": lz4.frame.compress,
}


@pytest.mark.parametrize("kind", sorted(FRAMES))
def test_every_cut_gives_a_growing_prefix(kind: str) -> None:
    data = compressible(400_000)
    frame = FRAMES[kind](data)
    assert lz4cut.salvage(frame, len(data)) == data
    previous = 0
    for cut in range(0, len(frame), 1777):
        got = lz4cut.salvage(frame[:cut], len(data))
        assert data.startswith(got)
        assert len(got) >= previous
        previous = len(got)
    # A cut just before the end mark leaves only the last sequence's bytes at stake.
    assert len(lz4cut.salvage(frame[: len(frame) - 12], len(data))) > len(data) - 100


def test_a_cut_block_gives_what_liblz4_cannot() -> None:
    data = compressible(500_000, seed=2)
    frame = lz4_compress(data)
    half = frame[: len(frame) // 2]
    assert lz4.frame.LZ4FrameDecompressor().decompress(half) == b""  # one block, cut: nothing
    got = lz4cut.salvage(half, len(data))
    assert 0.4 * len(data) < len(got) < 0.6 * len(data)


@settings(max_examples=60, deadline=None)
@given(st.binary(max_size=3000), st.data())
def test_arbitrary_data_and_cuts(data: bytes, pick: st.DataObject) -> None:
    frame = lz4.frame.compress(data + data[::-1], block_size=lz4.frame.BLOCKSIZE_MAX64KB)
    cut = pick.draw(st.integers(0, len(frame)))
    assert (data + data[::-1]).startswith(lz4cut.salvage(frame[:cut], 1 << 20))


def test_limit_and_errors() -> None:
    data = compressible(100_000)
    assert lz4cut.salvage(lz4_compress(data), 1000) == data[:1000]
    with pytest.raises(ValueError, match="not an LZ4 frame"):
        lz4cut.salvage(b"BZh91AY&SY", 100)
    with pytest.raises(ValueError, match="before its start"):
        lz4cut.decode_cut_block(bytes([0x10, ord("a"), 9, 0]))  # match 9 back after 1 byte
    assert lz4cut.decode_cut_block(bytes([0x14, ord("a"), 1, 0])) == b"a" * 9  # overlapping
