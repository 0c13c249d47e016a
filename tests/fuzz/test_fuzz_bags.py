"""Fuzz the bag readers with mutants of the corpus: byte flips, truncations, swapped records,
length fields set to 0xFFFFFFFF; through ``bag info``, ``echo -b``, ``convert`` and ``recover``.

Each command runs in this process through the CLI's own entry point. The invariant: a
documented exit code, no traceback, no "internal error", one error line exactly when the
exit code is not 0 (reports of what was done may precede it), and no case slower than
``CASE_SECONDS``.

A second test damages the structure (``tests/support/bagdamage.py``: a chunk or message
record header zeroed mid-file, index records, chunk infos and index entries damaged, chunks
swapped) and checks what comes out: only messages of the original, each exactly as it was;
every intact one; anything left out listed, ``bag cat`` exiting 6 then and 0 otherwise; and
``bag doctor`` flagging the file.
"""

from __future__ import annotations

import contextlib
import io
import signal
import struct
from collections import Counter
from pathlib import Path
from types import FrameType

import pytest
from hypothesis import given, seed, strategies as st

from rostools.bag.tools.findings import doctor
from rostools.cli import main
from tests.fuzz.conftest import FUZZ, SEED
from tests.support.bagdamage import BAG_KINDS, MCAP_KINDS, Source, load, messages_of, mutate
from tests.support.bagdata import write_sample
from tests.support.env import CORPUS, needs_corpus

pytestmark = needs_corpus

#: Small corpus files of every kind: plain, lz4 and bz2 bags, unindexed chunks, MCAPs.
SOURCES = [
    "ros1/embag/test_2.bag",
    "ros1/frost/compressed_lz4.bag",
    "ros1/ros_comm/rosbag_storage_test.bag",
    "ros1/rosbag.js/example-unsorted-chunks.bag",
    "ros1/matlab_rosbag/constants.bag",
    "ros1/webviz/bag-with-empty-message-definition.bag",
    "mcap/rosbag2/rosbag2_cpp/only_topics.mcap",
    "mcap/rosbag2/rosbag2_transport/test_bag_for_seek/test_bag_for_seek_0.mcap",
]
#: Exit codes a bad file may give (docs/scripting.md): error, usage, not found, data loss.
DOCUMENTED = {0, 1, 2, 3, 6}
CASE_SECONDS = 20


def _mutate(data: bytes, kind: str, at: int, size: int) -> bytes:
    at %= max(len(data), 1)
    if kind == "flip":
        return data[:at] + bytes([data[at] ^ 0xFF]) + data[at + 1 :] if data else data
    if kind == "truncate":
        return data[:at]
    if kind == "max_length":  # a u32 length field claiming 4 GiB
        return data[:at] + struct.pack("<I", 0xFFFFFFFF) + data[at + 4 :]
    if kind == "zero_length":
        return data[:at] + struct.pack("<I", 0) + data[at + 4 :]
    # swap two ranges of ``size`` bytes: records out of place
    other = (at * 7 + size) % max(len(data) - size, 1)
    first, second = sorted((at, other))
    if second < first + size or second + size > len(data):
        return data
    return (
        data[:first]
        + data[second : second + size]
        + data[first + size : second]
        + data[first : first + size]
        + data[second + size :]
    )


def _hang(signum: int, frame: FrameType | None) -> None:
    raise TimeoutError(f"a case ran past {CASE_SECONDS} s")


def _run(*args: str) -> tuple[int, str]:
    """``rostools ARGS`` in this process: its exit code and stderr."""
    out, err = io.StringIO(), io.StringIO()
    code: int | str | None = 0
    previous = signal.signal(signal.SIGALRM, _hang)
    signal.alarm(CASE_SECONDS)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                main(list(args))
            except SystemExit as stop:
                code = stop.code
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
    return int(code or 0), err.getvalue()


@seed(SEED)
@FUZZ
@given(
    st.sampled_from(SOURCES),
    st.sampled_from(["flip", "truncate", "max_length", "zero_length", "swap"]),
    st.integers(0, 2**20),
    st.integers(1, 64),
)
def test_mutant_bags_fail_cleanly(tmp: Path, source: str, kind: str, at: int, size: int) -> None:
    data = (CORPUS / source).read_bytes()
    suffix = Path(source).suffix
    mutant = tmp / f"mutant{suffix}"
    mutant.write_bytes(_mutate(data, kind, at, size))
    other = ".bag" if suffix == ".mcap" else ".mcap"
    for args in (
        ["bag", "info", str(mutant)],
        ["topic", "echo", "-b", str(mutant), "-a", "-n", "20", "-F", "json"],
        ["bag", "convert", str(mutant), str(tmp / f"converted{other}")],
        ["bag", "recover", str(mutant), str(tmp / f"recovered{suffix}")],
    ):
        code, err = _run(*args)
        assert code in DOCUMENTED, (args[:2], kind, at, code, err)
        assert "Traceback" not in err and "internal error" not in err, (args[:2], kind, at, err)
        # Reports of what was done ("recovered N messages", "wrote N of M") may come first; a
        # failure is one line, and only a failure says "rostools: ".
        errors = [ln for ln in err.splitlines() if ln.startswith("rostools: ")]
        assert len(errors) == (1 if code else 0), (args[:2], kind, at, err)
        for leftover in tmp.glob("converted*"):
            leftover.unlink()


@pytest.fixture(scope="module")
def tmp(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """One folder for every case (hypothesis calls the test many times per fixture)."""
    return tmp_path_factory.mktemp("mutants")


#: Corpus files for the structured damage: several chunks (unsorted ones too), or one.
STRUCTURED = [
    "ros1/embag/test_2.bag",
    "ros1/rosbag.js/example-unsorted-chunks.bag",
    "ros1/frost/compressed_lz4.bag",
    "ros1/frost/decompressed.bag",
]
#: Our own files beside them: many small chunks of every compression.
WRITTEN = ["none.bag", "bz2.bag", "lz4.bag", "zstd.mcap", "lz4.mcap", "none.mcap"]


@pytest.fixture(scope="module")
def sources(tmp: Path) -> dict[str, Source]:
    """Every source's layout and messages, read once."""
    found = {name: load(name, CORPUS / name) for name in STRUCTURED}
    for name in WRITTEN:
        compression = name.split(".")[0]
        path = tmp / f"source-{name}"
        write_sample(path, 300, compression=compression, chunk_size=3000)
        found[name] = load(name, path)
    return found


def _kinds(name: str) -> st.SearchStrategy[tuple[str, str]]:
    kinds = MCAP_KINDS if name.endswith(".mcap") else BAG_KINDS
    return st.tuples(st.just(name), st.sampled_from(kinds))


@seed(SEED)
@FUZZ
@given(
    st.sampled_from(STRUCTURED + WRITTEN).flatmap(_kinds),
    st.integers(0, 2**16),
    st.integers(0, 7),
)
def test_structured_damage_gives_every_intact_message(
    tmp: Path, sources: dict[str, Source], damage: tuple[str, str], pick: int, bit: int
) -> None:
    name, kind = damage
    source = sources[name]
    mutant = mutate(source, kind, pick, bit)
    if mutant is None:  # nothing of that kind in this file
        return
    path = tmp / ("damaged.mcap" if source.mcap else "damaged.bag")
    path.write_bytes(mutant.raw)
    case = (name, mutant.what)
    got, reader = messages_of(path)
    # Nothing wrong comes out: each message is one of the original's, times and bytes.
    assert not Counter(got) - Counter(source.messages), case
    # Every intact message does.
    assert not Counter(mutant.intact) - Counter(got), (case, reader.damage)
    if Counter(got) != Counter(source.messages):
        assert reader.damage, case  # what was left out is said
    if got != sorted(got, key=lambda m: m[1]):
        assert reader.notes, case  # out of time order only where the index said wrong
    # A read of one topic leaves chunks out by the index: it must hide nothing either.
    topics = sorted({m[0] for m in source.messages})
    topic = topics[pick % len(topics)]
    one, _ = messages_of(path, [topic])
    assert not Counter(one) - Counter(m for m in source.messages if m[0] == topic), case
    assert not Counter(m for m in mutant.intact if m[0] == topic) - Counter(one), case
    code, err = _run("bag", "cat", "--raw", str(path))
    assert code == (6 if reader.damage else 0), (case, code, err)
    assert "Traceback" not in err and "internal error" not in err, (case, err)
    checkup = doctor(path)
    assert not checkup.clean, case
