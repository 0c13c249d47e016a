"""Damaged corpus bags (issue 24, item 3): every intact message comes out, or the command says
what it left out and exits 6; ``doctor`` flags each damage. The real rosbag gives the reference.

- (a) one byte flipped in an lz4 bag's index: times come from the message records;
- (b) 1,764 zeroed bytes over a chunk header mid-file: reading goes on at the next record;
- (c) two whole chunks (with their index records) swapped in a bz2 bag: all 6,121 messages,
  as ``rosbag reindex`` gets them.

Issue 32, item 2: an index that points at the wrong records.

- (d) a bz2 bag whose chunk info names the next chunk: rosbag reads that chunk twice and the
  other never; ours and ``rosbag reindex`` read all 6,121 messages once;
- (e) a connection record whose index copy has another md5sum (and definition) than the
  chunk's: ``doctor`` says so, and ``recover`` keeps the chunk's.
"""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path
from typing import Any

from rostools.bag.formats import rosbag1_format as fmt
from rostools.bag.formats.access import open_bag
from rostools.bag.tools.findings import doctor
from rostools.bag.tools.recover import recover
from rostools.msgs.store import md5_of
from rostools.wire.header import encode_fields, split_fields
from tests.support.bagdata import bag_records, chunk_spans, digest, swap_spans
from tests.support.env import CORPUS, SYSTEM_PYTHON, needs_corpus, needs_ros1, run_cli

pytestmark = needs_corpus

ROS1 = CORPUS / "ros1"
LZ4 = ROS1 / "frost" / "compressed_lz4.bag"
TEST1 = ROS1 / "robot_localization" / "test1.bag"
TEST2 = ROS1 / "robot_localization" / "test2.bag"
DUMP = Path(__file__).parent.parent / "support" / "rosbag_dump.py"
DATA_LOSS = 6


def flip_index_time(src: Path, dst: Path) -> int:
    """Flip one bit of an index entry's seconds (+2**26 s); the original time, in ns."""
    data = bytearray(src.read_bytes())
    index = next(r for r in bag_records(bytes(data)) if r[1] == fmt.OP_INDEX_DATA)
    entry = index[3] + fmt.INDEX_ENTRY_SIZE * (fmt.u32_field(index[2], "count") - 1)
    secs, nsecs = fmt.TIME.unpack_from(data, entry)
    data[entry + 3] ^= 0x04
    dst.write_bytes(bytes(data))
    return int(secs) * 1_000_000_000 + int(nsecs)


def zero_chunk_header(src: Path, dst: Path, nth: int, size: int = 1764) -> tuple[int, int, int]:
    """Zero ``size`` bytes from the start of chunk ``nth``; (its position, start, end ns)."""
    data = bytearray(src.read_bytes())
    records = bag_records(bytes(data))
    pos = [r[0] for r in records if r[1] == fmt.OP_CHUNK][nth]
    info = next(
        r[2]
        for r in records
        if r[1] == fmt.OP_CHUNK_INFO and fmt.u64_field(r[2], "chunk_pos") == pos
    )
    data[pos : pos + size] = bytes(size)
    dst.write_bytes(bytes(data))
    return pos, fmt.time_field(info, "start_time"), fmt.time_field(info, "end_time")


def swap_chunks(src: Path, dst: Path, i: int, j: int) -> None:
    """Swap chunks ``i`` < ``j``, each with the index records that follow it."""
    data = src.read_bytes()
    spans = chunk_spans(data)
    dst.write_bytes(swap_spans(data, spans[i], spans[j]))


def point_info_elsewhere(src: Path, dst: Path, nth: int, other: int) -> tuple[int, int]:
    """Make the chunk info of chunk ``nth`` name chunk ``other``; (their positions)."""
    data = bytearray(src.read_bytes())
    records = bag_records(bytes(data))
    chunks = [r[0] for r in records if r[1] == fmt.OP_CHUNK]
    info = next(
        r
        for r in records
        if r[1] == fmt.OP_CHUNK_INFO and fmt.u64_field(r[2], "chunk_pos") == chunks[nth]
    )
    at = data.index(b"chunk_pos=" + fmt.U64.pack(chunks[nth]), info[0]) + len(b"chunk_pos=")
    data[at : at + 8] = fmt.U64.pack(chunks[other])
    dst.write_bytes(bytes(data))
    return chunks[nth], chunks[other]


def retype_index_copy(src: Path, dst: Path) -> tuple[str, str]:
    """Give the index's copy of connection 0 another definition, with its own md5sum.

    The copy stays consistent (its md5sum is its definition's), so only a look at the chunk's
    copy tells them apart. (the chunk's md5sum, the index's).
    """
    raw = src.read_bytes()
    index_pos = fmt.u64_field(bag_records(raw)[0][2], "index_pos")
    pos, op, fields, data, dlen = bag_records(raw, index_pos)[0]
    assert op == fmt.OP_CONNECTION and fmt.u32_field(fields, "conn") == 0
    header = {k: v.decode() for k, v in split_fields(raw[data : data + dlen]).items()}
    theirs = header["md5sum"]
    header["message_definition"] = header["message_definition"].replace(
        " orientation\n", " attitude\n", 1
    )
    header["md5sum"] = md5_of(header["type"], header["message_definition"])
    assert header["md5sum"] not in ("", theirs)
    record = fmt.encode_record(fields, encode_fields(header))
    dst.write_bytes(raw[:pos] + record + raw[data + dlen :])  # the index's first record
    return theirs, header["md5sum"]


def ours(path: Path) -> list[list[Any]]:
    with open_bag(path) as reader:
        return [[c.topic, t, digest(bytes(d))] for c, t, d in reader.messages()]


def rosbag_streams(*paths: Path) -> dict[str, Any]:
    """What the real rosbag.Bag reads from each file: path -> {"stream": ...} or {"error": ...}."""
    proc = subprocess.run(
        [SYSTEM_PYTHON, str(DUMP), *map(str, paths)],
        capture_output=True, text=True, timeout=600, check=True,
    )  # fmt: skip
    return dict(json.loads(proc.stdout))


@needs_ros1
def test_a_message_times_come_from_the_records(tmp_path: Path) -> None:
    bad = tmp_path / "flipped.bag"
    true_time = flip_index_time(LZ4, bad)
    views = rosbag_streams(bad, LZ4)
    theirs, original = views[str(bad)]["stream"], views[str(LZ4)]["stream"]
    # rosbag returns the records' times (it orders by the index's, so the message whose
    # entry is damaged comes last among its equals): the original messages, times and all.
    assert max(m[1] for m in theirs) == 99_000_100_000 and true_time in [m[1] for m in theirs]
    assert sorted(theirs) == sorted(original) and len(original) == 300
    assert ours(bad) == original
    # The disagreement is said, never resolved in silence.
    with open_bag(bad) as reader:
        for _ in reader.messages():
            pass
        assert any("index" in n and "records" in n for n in reader.notes), reader.notes
    report = recover(bad, tmp_path / "recovered.bag")
    assert report.messages == 300 and report.complete and report.notes
    with open_bag(tmp_path / "recovered.bag") as reader:
        assert reader.info().end_ns == 99_000_100_000
    assert ours(tmp_path / "recovered.bag") == original
    checkup = doctor(bad)
    assert not checkup.clean and any("index" in f for f in checkup.findings), checkup.findings
    done = run_cli("bag", "cat", str(bad), "--raw")
    assert done.returncode == 0, done.stderr
    assert [json.loads(line)["log_time"] for line in done.stdout.splitlines()] == [
        m[1] for m in original
    ]
    assert "note:" in done.stderr and "index" in done.stderr


@needs_ros1
def test_b_a_damaged_header_mid_file_hides_nothing_else(tmp_path: Path) -> None:
    bad = tmp_path / "zeroed.bag"
    pos, start, end = zero_chunk_header(TEST1, bad, nth=5)
    original = rosbag_streams(TEST1)[str(TEST1)]["stream"]
    intact = [m for m in original if not start <= m[1] <= end]
    assert len(original) == 16806 and len(intact) == 15044
    assert ours(bad) == intact
    with open_bag(bad) as reader:
        assert reader.info().message_count == 15044
        assert any(str(pos) in d for d in reader.damage), reader.damage
    checkup = doctor(bad)
    assert not checkup.clean and checkup.messages == 15044
    assert any(str(pos) in f for f in checkup.findings), checkup.findings
    info = run_cli("bag", "info", str(bad))
    assert info.returncode == DATA_LOSS and "15044" in info.stdout, info.stderr
    assert info.stderr.count("rostools: ") == 1 and str(pos) in info.stderr
    cat = run_cli("bag", "cat", str(bad), "--raw")
    assert cat.returncode == DATA_LOSS and len(cat.stdout.splitlines()) == 15044
    for args in (
        ["convert", str(bad), str(tmp_path / "c.mcap")],
        ["merge", str(tmp_path / "m.bag"), str(bad)],
        ["filter", str(bad), str(tmp_path / "f.bag"), "True"],
    ):
        done = run_cli("bag", *args)
        assert done.returncode == DATA_LOSS, (args, done.stderr)
        assert "wrote 15044 of 15044" in done.stderr and str(pos) in done.stderr
        assert "Traceback" not in done.stderr
    assert ours(tmp_path / "m.bag") == intact
    assert ours(tmp_path / "c.mcap") == intact


@needs_ros1
def test_c_swapped_chunks_as_rosbag_reindex_reads_them(tmp_path: Path) -> None:
    bad = tmp_path / "swapped.bag"
    swap_chunks(TEST2, bad, 0, 2)  # the first chunk holds the connection records
    theirs = tmp_path / "reindexed.bag"
    shutil.copy(bad, theirs)
    subprocess.run(["rosbag", "reindex", str(theirs)], capture_output=True, check=True)
    views = rosbag_streams(theirs, TEST2)
    reference = views[str(TEST2)]["stream"]
    # rosbag reindex gets every message back (it yields the chunks in file order).
    assert sorted(views[str(theirs)]["stream"]) == sorted(reference) and len(reference) == 6121
    assert ours(bad) == reference
    report = recover(bad, tmp_path / "recovered.bag")
    assert report.messages == 6121 and report.complete
    assert ours(tmp_path / "recovered.bag") == reference
    done = run_cli("bag", "merge", str(tmp_path / "m.bag"), str(bad))
    assert done.returncode == 0 and "wrote 6121 of 6121" in done.stderr, done.stderr
    assert "note:" in done.stderr
    checkup = doctor(bad)
    assert not checkup.clean and checkup.messages == 6121


@needs_ros1
def test_d_a_chunk_info_naming_another_chunk_hides_nothing(tmp_path: Path) -> None:
    bad = tmp_path / "misplaced.bag"
    lost, _ = point_info_elsewhere(TEST2, bad, 2, 3)
    theirs = tmp_path / "reindexed.bag"
    shutil.copy(bad, theirs)
    subprocess.run(["rosbag", "reindex", str(theirs)], capture_output=True, check=True)
    views = rosbag_streams(bad, theirs, TEST2)
    reference = views[str(TEST2)]["stream"]
    # rosbag reads the next chunk twice and the one at `lost` never; its reindex gets every
    # message back.
    misread = views[str(bad)]["stream"]
    assert len(misread) == 6121 and len({tuple(m) for m in misread}) < 6121
    assert sorted(views[str(theirs)]["stream"]) == sorted(reference) and len(reference) == 6121
    assert ours(bad) == reference
    index_pos = fmt.u64_field(bag_records(bad.read_bytes())[0][2], "index_pos")
    with open_bag(bad) as reader:
        assert reader.notes == [
            f"unindexed: its index at {index_pos} is damaged (no chunk info names the chunk at"
            f" {lost}); read by scanning its chunks"
        ]
    checkup = doctor(bad)
    assert not checkup.clean and checkup.messages == 6121
    assert any(str(lost) in f for f in checkup.findings), checkup.findings
    report = recover(bad, tmp_path / "recovered.bag")
    assert report.messages == 6121 and report.complete
    assert ours(tmp_path / "recovered.bag") == reference
    assert (
        rosbag_streams(tmp_path / "recovered.bag")[str(tmp_path / "recovered.bag")]["stream"]
        == reference
    )
    for args in (
        ["cat", str(bad), "--raw"],
        ["merge", str(tmp_path / "m.bag"), str(bad)],
        ["reindex", str(bad)],
    ):
        done = run_cli("bag", *args)
        assert done.returncode == 0 and f"chunk at {lost}" in done.stderr, (args, done.stderr)
    assert ours(tmp_path / "m.bag") == reference
    assert ours(bad) == reference and ours(tmp_path / "misplaced.orig.bag") == reference
    assert doctor(bad).clean  # reindexed in place


@needs_ros1
def test_e_a_chunks_connection_record_unlike_the_index_copy(tmp_path: Path) -> None:
    bad = tmp_path / "retyped.bag"
    chunk_md5, index_md5 = retype_index_copy(TEST2, bad)
    views = rosbag_streams(bad, TEST2)
    # rosbag takes the index's copy; the messages are the chunk's type
    assert views[str(bad)]["headers"][0][1]["md5sum"] == index_md5
    checkup = doctor(bad)
    assert not checkup.clean, checkup.findings
    said = f"md5sum {chunk_md5!r} against {index_md5!r}"
    assert [f for f in checkup.findings if said in f] == [
        f"connection 0 (/imu/data): its record in the chunk at 4117 differs from the one in"
        f" the index ({said}, message_definition); the one in the index is used"
    ]
    report = recover(bad, tmp_path / "recovered.bag")
    assert report.complete and report.messages == 6121
    assert any("the one in the chunk at 4117 is used" in n for n in report.notes), report.notes
    fixed = rosbag_streams(tmp_path / "recovered.bag")[str(tmp_path / "recovered.bag")]
    assert fixed["headers"] == views[str(TEST2)]["headers"]
    assert fixed["stream"] == views[str(TEST2)]["stream"]
    assert doctor(tmp_path / "recovered.bag").clean
