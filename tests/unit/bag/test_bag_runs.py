"""A ``.bag`` read a chunk at a time (``runs``: ``runs``) gives exactly what
``messages`` gives: the same messages in the same order, the same notes and the same damage,
for regular bags, chunks that overlap in time, damaged bytes and the corpus."""

from __future__ import annotations

import random
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from rostools.bag.formats.access import open_bag, open_writer
from rostools.bag.formats.rosbag1_reader import Bag1Reader
from rostools.bag.formats.runs import Run
from rostools.errors import RostoolsError
from tests.support.bagdata import SAMPLE_CONNECTIONS, write_sample
from tests.support.env import CORPUS

Read = tuple[list[tuple[int, bytes]], list[str], list[str]] | str


def _read(path: Path, bulk: bool, topics: set[str] | None, window: tuple[Any, Any]) -> Read:
    """(messages, notes, damage) of one way of reading, or the one line it failed with.

    The chunk-at-a-time way also gives its messages as one array when they share a size.
    """
    try:
        with open_bag(path) as reader:
            chosen = [c for c in reader.connections if topics is None or c.topic in topics]
            if bulk:
                got: list[tuple[int, bytes]] = []
                for run in reader.runs(chosen, *window):
                    data = [bytes(d) for d in run.data()]
                    got += zip(run.times.tolist(), data, strict=True)
                    rows = run.rows(len(data[0]))  # copied out with the headers, or now
                    if rows is not None:
                        assert [r.tobytes() for r in rows] == data
            else:
                got = [(t, bytes(d)) for _, t, d in reader.messages(None, *window, chosen)]
            return got, list(reader.notes), list(reader.damage)
    except RostoolsError as err:
        return f"{type(err).__name__}: {err}"


def assert_same(
    path: Path, topics: set[str] | None = None, window: tuple[Any, Any] = (None, None)
) -> Read:
    """Both ways read ``path`` alike; what they read."""
    slow = _read(path, False, topics, window)
    assert _read(path, True, topics, window) == slow
    return slow


@pytest.mark.parametrize("compression", ["none", "bz2", "lz4"])
def test_a_regular_bag_reads_alike_for_any_topics_and_window(
    tmp_path: Path, compression: str
) -> None:
    sample = write_sample(tmp_path / "x.bag", 400, compression=compression, chunk_size=3000)
    slow = assert_same(sample.path)
    assert not isinstance(slow, str) and len(slow[0]) == 400 and slow[1:] == ([], [])
    assert_same(sample.path, {"/chatter"})
    assert_same(sample.path, {"/count", "/point"}, (50_000_150, 300_000_900))
    assert_same(sample.path, {"/nothing"})


def test_chunks_that_overlap_in_time_are_merged_alike(tmp_path: Path) -> None:
    path = tmp_path / "overlap.bag"
    with open_writer(path, chunk_size=2000) as writer:
        conns = [writer.add_connection(*c[:4], callerid=c[4]) for c in SAMPLE_CONNECTIONS[2:]]
        rng = random.Random(7)
        for i in range(600):  # times that wander back: later chunks reach into earlier ones
            t = max(0, i * 1000 + rng.randint(-80_000, 80_000))
            writer.write(conns[i % 2], t, (i % 2 and b"\0" * 24) or i.to_bytes(4, "little"))
    slow = assert_same(path)
    assert not isinstance(slow, str)
    times = [t for t, _ in slow[0]]
    assert times == sorted(times) and len(times) == 600
    assert_same(path, {"/count"}, (100_000, 400_000))


@pytest.mark.parametrize("compression", ["none", "bz2", "lz4"])
def test_damaged_bags_read_alike(tmp_path: Path, compression: str) -> None:
    raw = write_sample(tmp_path / "x.bag", 300, compression=compression, chunk_size=3000)
    data = raw.path.read_bytes()
    rng = random.Random(f"runs{compression}")
    bad = tmp_path / "bad.bag"
    damaged_reads = 0
    for _ in range(40):
        damaged = bytearray(data)
        for _ in range(rng.randint(1, 3)):
            at = rng.randrange(len(data))
            damaged[at : at + rng.randint(1, 8)] = rng.randbytes(rng.randint(1, 8))
        bad.write_bytes(bytes(damaged))
        read = assert_same(bad, {"/chatter", "/point"})
        damaged_reads += not isinstance(read, str) and bool(read[1] or read[2])
    assert damaged_reads  # the mutants reached the careful path, not only the regular one


def _corpus_bags() -> list[Path]:
    return sorted((CORPUS / "ros1").rglob("*.bag")) if CORPUS.is_dir() else []


@pytest.mark.parametrize("path", _corpus_bags(), ids=lambda p: str(p.relative_to(CORPUS)))
def test_every_corpus_bag_reads_alike_topic_by_topic(path: Path) -> None:
    # A file that is no bag fails both ways with the same line (assert_same compares them).
    if isinstance(assert_same(path), str):
        return
    with open_bag(path) as reader:
        assert isinstance(reader, Bag1Reader)
        topics = sorted({c.topic for c in reader.connections})
    for topic in topics:
        assert_same(path, {topic})


@pytest.mark.parametrize("pattern", ["one", "even", "stretches", "backwards", "scattered"])
def test_rows_of_a_chunk_are_its_messages_bytes(pattern: str) -> None:
    rng = random.Random(pattern)
    size = 12
    buf = rng.randbytes(20_000)
    if pattern == "one":
        starts = [100]
    elif pattern == "even":
        starts = list(range(0, 15_000, 40))
    elif pattern == "stretches":  # runs of one step broken by others, as topics interleave
        starts, at = [], 0
        while at < 19_000:
            starts += range(at, at + 30 * 20, 20)
            at += 30 * 20 + rng.randrange(1, 300)
    elif pattern == "backwards":
        starts = list(range(15_000, 0, -25))
    else:
        starts = rng.sample(range(19_000), 500)
    run = Run(
        np.zeros(len(starts), np.int64), None, buf, np.array(starts), np.full(len(starts), size)
    )
    rows = run.rows(size)
    assert rows is not None
    assert [bytes(r) for r in rows] == [buf[a : a + size] for a in starts]
    assert run.rows(size + 1) is None
