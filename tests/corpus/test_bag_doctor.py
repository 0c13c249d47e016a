"""``bag doctor`` (issue 15) on the whole corpus and on mutated copies (fixed seed)."""

from __future__ import annotations

import json
import random
from pathlib import Path

import pytest

from rostools.bag.formats.mcap_reader import McapReader
from rostools.bag.tools.findings import doctor
from rostools.bag.tools.ops import convert
from rostools.bag.tools.options import CopyOptions
from tests.support.env import CORPUS, needs_corpus, run_cli

#: The corpus files that are damaged, or not bags at all: each must have findings.
DAMAGED = {
    "ros1/rosbag-rs/dummy.bag", "ros1/rosbag.js/empty-file.bag", "ros1/rosbag2/test.bag",
    "ros1/webviz/invalid.bag", "ros1-derived/embag_test_cut_at_index_pos.bag",
    "ros1-derived/example_cut_at_index_pos.bag", "ros1-derived/test1_cut_at_60pct.bag",
}  # fmt: skip


@needs_corpus
def test_the_corpus_is_clean_but_for_its_damaged_files() -> None:
    files = sorted([*CORPUS.rglob("*.bag"), *CORPUS.rglob("*.mcap")])
    dirty = {str(p.relative_to(CORPUS)) for p in files if not doctor(p).clean}
    assert dirty == DAMAGED
    cut = doctor(CORPUS / "ros1-derived" / "test1_cut_at_60pct.bag")
    assert cut.recover_helps and any("cut short" in f for f in cut.findings)
    # Out of time order within a chunk is legal (rosbag.js's example.bag, MCAP's TenMessages):
    # a note, and the file stays clean.
    unsorted = doctor(CORPUS / "ros1" / "rosbag.js" / "example.bag")
    assert unsorted.clean and unsorted.notes == ["chunk at 4117: 33 messages out of time order"]
    ten = next((CORPUS / "mcap" / "conformance" / "TenMessages").glob("*-ch.mcap"))
    assert doctor(ten).clean and "out of time order" in doctor(ten).notes[0]


@needs_corpus
def test_cli_lines_and_exit_codes() -> None:
    good = CORPUS / "ros1" / "roswire" / "example.bag"
    bad = CORPUS / "ros1-derived" / "example_cut_at_index_pos.bag"
    clean = run_cli("bag", "doctor", str(good))
    assert clean.returncode == 0 and clean.stdout == f"{good}: clean (1038 messages)\n"
    both = run_cli("bag", "doctor", str(good), str(bad), "-F", "json")
    assert both.returncode == 1 and "Traceback" not in both.stderr
    data = json.loads(both.stdout)
    assert [d["clean"] for d in data] == [True, False] and data[1]["recover_helps"]


@needs_corpus
def test_progress_is_reported_as_messages_are_read(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr("rostools.bag.tools.findings.PROGRESS_STEP", 100)
    calls: list[tuple[int, int]] = []
    report = doctor(CORPUS / "ros1" / "roswire" / "example.bag", lambda *a: calls.append(a))
    assert calls[0] == (100, 1038) and calls[-1] == (1038, 1038) and len(calls) == 11
    assert report.messages == 1038


def _mutants(data: bytes, rng: random.Random, lo: int, hi: int) -> list[tuple[str, bytes]]:
    """Truncated copies, and copies with a flipped byte or two swapped blocks in [lo, hi)."""
    out = [(f"cut at {n}", data[:n]) for n in sorted(rng.sample(range(64, len(data)), 6))]
    for _ in range(6):
        i = rng.randrange(lo, hi)
        out.append((f"flip at {i}", data[:i] + bytes([data[i] ^ 0x5A]) + data[i + 1 :]))
    for _ in range(3):
        i, j = sorted(rng.sample(range(lo, hi - 64), 2))
        if j - i >= 64:
            swapped = (
                data[:i] + data[j : j + 64] + data[i + 64 : j] + data[i : i + 64] + data[j + 64 :]
            )
            out.append((f"swap {i}<->{j}", swapped))
    return out


def _mcap_with_crcs(src: Path, dst: Path) -> Path:
    """``src`` as MCAP, written by our writer (which writes every CRC), in small chunks."""
    convert(src, dst, CopyOptions(compression="zstd", chunk_size=64 * 1024))
    return dst


@needs_corpus
@pytest.mark.parametrize("suffix", ["bag", "mcap"])
def test_mutated_copies_never_crash_it(tmp_path: Path, suffix: str) -> None:
    """A cut file is always named; in MCAP, any change to a chunk's bytes is (its CRC)."""
    src = CORPUS / "ros1" / "roswire" / "example.bag"
    if suffix == "mcap":
        src = _mcap_with_crcs(src, tmp_path / "x.mcap")
        with McapReader(src) as reader:
            first = min(reader.chunk_indexes, key=lambda c: c.chunk_start_offset)
        lo, hi = first.chunk_start_offset + 80, first.chunk_start_offset + first.chunk_length
    data = src.read_bytes()
    if suffix == "bag":
        lo, hi = 13, len(data)
    for i, (what, mutant) in enumerate(_mutants(data, random.Random(1500), lo, hi)):
        path = tmp_path / f"m{i}.{suffix}"
        path.write_bytes(mutant)
        report = doctor(path)  # raises nothing, whatever the bytes
        if what.startswith("cut") or suffix == "mcap":
            assert not report.clean, what
