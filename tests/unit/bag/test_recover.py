"""Recovery of cut-short and killed recordings, in both formats."""

from __future__ import annotations

import os
import random
import signal
import struct
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from rostools.bag.formats.access import bag_info, open_bag, open_writer
from rostools.bag.formats.mcap_reader import McapReader
from rostools.bag.formats.model import BagFormatError, BagUsageError, UnsupportedBagError
from rostools.bag.formats.rosbag1_reader import Bag1Reader
from rostools.bag.tools.recover import RecoverReport, recover, reindex
from rostools.errors import DataLossError
from tests.support.bagdata import (
    STRING_MD5,
    bag_records,
    first_chunk_data,
    handmade_mcap,
    read_stream,
    write_sample,
)
from tests.support.env import ROOT
from tests.support.reap import reap_with_pytest

CASES = [
    ("x.bag", "none"),
    ("x.bag", "lz4"),
    ("x.bag", "bz2"),
    ("x.mcap", "zstd"),
    ("x.mcap", "none"),
]


@pytest.mark.parametrize(("name", "compression"), CASES)
def test_cut_files_recover_a_prefix(tmp_path: Path, name: str, compression: str) -> None:
    sample = write_sample(tmp_path / name, 600, compression=compression, chunk_size=6000)
    raw = sample.path.read_bytes()
    suffix = Path(name).suffix
    start = 4117 + 40 if suffix == ".bag" else 60
    recovered_counts = []
    for cut in range(start, len(raw), 1499):
        part = tmp_path / f"cut{suffix}"
        part.write_bytes(raw[:cut])
        out = tmp_path / f"out{cut}{suffix}"
        try:
            report = recover(part, out)
        except BagFormatError:  # cut before the first whole message: nothing to write
            assert not recovered_counts or recovered_counts[-1] == 0
            recovered_counts.append(0)
            continue
        got = read_stream(out)
        assert got == sample.stream[: len(got)]
        assert report.messages == len(got)
        assert bag_info(out).indexed
        recovered_counts.append(len(got))
    assert recovered_counts == sorted(recovered_counts)
    assert recovered_counts[-1] > 500


#: Every chunk compression of both formats.
MID_CHUNK = [
    ("x.bag", "none"),
    ("x.bag", "lz4"),
    ("x.bag", "bz2"),
    ("x.mcap", "none"),
    ("x.mcap", "zstd"),
    ("x.mcap", "lz4"),
]
#: Where in its chunk a cut first leaves something to salvage, and how many cuts: after the
#: first compression block (bz2 900 kB, zstd 128 KiB of input), or the first record. bz2
#: takes 0.4 s a read here.
FIRST_CUT = {"bz2": (0.95, 2), "zstd": (0.2, 6)}


def _one_chunk(path: Path, compression: str) -> tuple[list[tuple[str, str, int, bytes]], int, int]:
    """50 messages of 20 kB of random bytes in one chunk: (stream, chunk start, chunk length).

    Random bytes do not compress, so lz4 and zstd store their blocks raw: a chunk's records
    then lie in the file as they are, with a block header inside some of them.
    """
    rng = random.Random(26)
    stream = []
    with open_writer(path, compression=compression, chunk_size=1 << 26) as writer:
        conn = writer.add_connection(
            "/blob", "std_msgs/String", STRING_MD5, "string data\n", callerid="/blobber"
        )
        for i in range(50):
            text = rng.randbytes(20_000)
            data = struct.pack("<I", len(text)) + text
            writer.write(conn, i * 1000, data)
            stream.append(("/blob", "/blobber", i * 1000, data))
    with open_bag(path) as reader:
        if isinstance(reader, McapReader):
            [index] = reader.chunk_indexes
            return stream, index.chunk_start_offset, index.chunk_length
        assert isinstance(reader, Bag1Reader)
        [chunk] = reader.chunks
        return stream, chunk.data_pos, chunk.data_len


@pytest.mark.parametrize(("name", "compression"), MID_CHUNK)
def test_a_chunk_cut_in_the_middle_gives_what_it_holds(
    tmp_path: Path, name: str, compression: str
) -> None:
    # the defects: a cut uncompressed chunk was read as loose records and said "0 messages
    # salvaged from it"; an lz4 or zstd chunk of raw blocks was read the same way, and a
    # message with a block header inside it came out as a message of 20 kB of wrong bytes
    suffix = Path(name).suffix
    stream, start, length = _one_chunk(tmp_path / name, compression)
    raw = (tmp_path / name).read_bytes()
    first, cuts = FIRST_CUT.get(compression, (0.05, 6))
    salvaged = []
    for k in range(cuts):
        cut = start + int(length * (first + (0.995 - first) * k / (cuts - 1)))
        (tmp_path / f"cut{suffix}").write_bytes(raw[:cut])
        out = tmp_path / f"out{cut}{suffix}"
        report = recover(tmp_path / f"cut{suffix}", out, compression="none")  # fast to write
        got = read_stream(out)
        assert len(got) > 0, f"nothing salvaged from a cut at {cut - start} of {length} bytes"
        assert report.messages == len(got)
        assert got == stream[: len(got)]  # byte for byte, in order
        assert not report.complete
        if suffix == ".bag":  # the damage line counts what the output holds
            [line] = [x for x in report.lost if "cut short" in x and "salvaged" in x]
            assert line.endswith(f"; {len(got)} messages salvaged from it")
        if compression == "none":  # every message wholly before the cut, and no more
            assert len(got) == sum(raw.find(m[3]) + len(m[3]) <= cut for m in stream)
        salvaged.append(len(got))
    assert salvaged == sorted(salvaged)  # more bytes never salvage less
    assert salvaged[-1] >= 40


def test_uncompressed_bag_cut_mid_chunk_keeps_every_whole_record(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.bag", 200)  # one chunk
    raw = sample.path.read_bytes()
    data_at, data_len = first_chunk_data(raw)
    records = bag_records(raw, data_at, data_at + data_len)  # the chunk's, read whole
    ends = [data + n for _, op, _, data, n in records if op == 2]  # messages'
    assert len(ends) == 200
    for cut in range(4200, len(raw), 211):
        (tmp_path / "cut.bag").write_bytes(raw[:cut])
        whole = sum(end <= cut for end in ends)
        try:
            report = recover(tmp_path / "cut.bag", tmp_path / f"o{cut}.bag")
        except BagFormatError:  # only when the cut leaves no record whole after the header
            assert cut < records[0][3] + records[0][4]
            continue
        assert report.messages == len(read_stream(tmp_path / f"o{cut}.bag")) == whole
        if cut < len(raw) - 2000:
            assert not report.complete  # the record cut in two is reported lost
            with pytest.raises(DataLossError, match="lost"):
                report.raise_if_lost()
    assert whole == 200  # rosbag reindex salvages 0 here: its only chunk is unterminated


def test_lz4_bag_cut_mid_chunk_keeps_the_records_before_the_cut(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.bag", 2000, compression="lz4")  # one chunk, one block
    raw = sample.path.read_bytes()
    start, length = first_chunk_data(raw)
    (tmp_path / "cut.bag").write_bytes(raw[: start + length // 2])
    report = recover(tmp_path / "cut.bag", tmp_path / "out.bag")
    got = read_stream(tmp_path / "out.bag")
    assert got == sample.stream[: len(got)]
    assert 0.3 * 2000 < report.messages < 2000  # liblz4 alone salvages none of this chunk
    assert not report.complete


def test_recovering_a_sound_bag_loses_nothing(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.bag", 100, compression="lz4")
    report = reindex(sample.path, tmp_path / "y.bag")
    assert report.complete
    assert report.was_indexed
    report.raise_if_lost()
    assert [c.compression for c in bag_info(tmp_path / "y.bag").compression] == ["lz4"]
    assert read_stream(tmp_path / "y.bag") == sample.stream


def test_recover_into_the_other_format(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.bag", 100, close=False)
    report = recover(sample.path, tmp_path / "y.mcap")
    assert report.format == "bag"
    assert not report.was_indexed
    assert read_stream(tmp_path / "y.mcap") == sample.stream


def test_nothing_to_recover(tmp_path: Path) -> None:
    raw = write_sample(tmp_path / "x.bag", 10, close=False).path.read_bytes()
    (tmp_path / "header-only.bag").write_bytes(raw[:4117])
    with pytest.raises(BagFormatError):
        recover(tmp_path / "header-only.bag", tmp_path / "out.bag")
    assert not (tmp_path / "out.bag").exists()


CHILD = textwrap.dedent(
    """
    import sys, time
    sys.path.insert(0, {root!r})
    from tests.support.bagdata import SAMPLE_CONNECTIONS, message
    from rostools.bag.formats.access import open_writer

    path, compression = sys.argv[1], sys.argv[2]
    writer = open_writer(path, compression=compression, chunk_size=20_000)
    conns = [writer.add_connection(t, k, m, d, callerid=c, latching=l)
             for t, k, m, d, c, l in SAMPLE_CONNECTIONS]
    i = 0
    for _ in range(3):
        for _ in range(700):
            k, t, data = message(i)
            writer.write(conns[k], t, data)
            i += 1
        writer.flush()
        print(i, flush=True)
    for _ in range(50):  # more messages that stay in the writer's hands
        k, t, data = message(i)
        writer.write(conns[k], t, data)
        i += 1
    print("ready", flush=True)
    time.sleep(60)
    """
)


@pytest.mark.parametrize(
    ("name", "compression"), [("k.bag", "none"), ("k.bag", "lz4"), ("k.mcap", "zstd")]
)
def test_killed_writer_is_recovered(tmp_path: Path, name: str, compression: str) -> None:
    path = tmp_path / name
    code = CHILD.format(root=str(ROOT))
    child = subprocess.Popen(
        [sys.executable, "-c", code, str(path), compression],
        stdout=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    reap_with_pytest(child.pid)
    try:
        assert child.stdout is not None
        lines = [child.stdout.readline().strip() for _ in range(4)]
        assert lines[-1] == "ready", lines
        flushed = int(lines[-2])
    finally:
        os.kill(child.pid, signal.SIGKILL)
        child.wait(timeout=30)
    assert child.returncode == -signal.SIGKILL
    report = recover(path, tmp_path / ("out" + path.suffix))
    expected = write_sample(tmp_path / ("ref" + path.suffix), flushed + 50).stream
    got = read_stream(tmp_path / ("out" + path.suffix))
    assert len(got) >= flushed  # every message handed to the OS is back
    assert got == expected[: len(got)]
    assert report.messages == len(got)


@pytest.mark.parametrize(("name", "compression"), [("x.bag", "bz2"), ("x.mcap", "zstd")])
def test_a_corrupt_chunk_is_skipped_and_reported(
    tmp_path: Path, name: str, compression: str
) -> None:
    sample = write_sample(tmp_path / name, 600, compression=compression, chunk_size=6000)
    raw = bytearray(sample.path.read_bytes())
    with open_bag(sample.path) as reader:
        assert reader.info().chunk_count > 3
        if isinstance(reader, McapReader):
            index = reader.chunk_indexes[len(reader.chunk_indexes) // 2]
            middle = index.chunk_start_offset + index.chunk_length // 2
        else:
            assert isinstance(reader, Bag1Reader)
            chunk = reader.chunks[len(reader.chunks) // 2]
            middle = chunk.data_pos + chunk.data_len // 2
    raw[middle : middle + 64] = b"\xa5" * 64  # garbage in the middle of a compressed chunk
    bad = tmp_path / ("bad" + Path(name).suffix)
    bad.write_bytes(bytes(raw))
    # Any read skips the chunk and lists it (issue 24): it does not stop at it.
    with open_bag(bad) as reader:
        assert 300 < len(list(reader.messages())) < 600
        assert reader.damage
    report = recover(bad, tmp_path / ("out" + Path(name).suffix))
    assert not report.complete
    got = read_stream(tmp_path / ("out" + Path(name).suffix))
    assert 300 < len(got) < 600
    assert set(got) < set(sample.stream)


def _cdr_mcap(path: Path) -> Path:
    """An unindexed MCAP of one ROS 2 channel (CDR), as a ros2 bag recorder writes them."""
    from rostools.bag.formats import mcap_format as fmt

    schema = fmt.encode_schema(1, "std_msgs/msg/String", "ros2msg", b"string data")
    return handmade_mcap(path, "ros2", schema + fmt.encode_channel(1, 1, "/x", "cdr", {}))


def test_ros2_messages_are_recovered_into_mcap_only(tmp_path: Path) -> None:
    src = _cdr_mcap(tmp_path / "cdr.mcap")
    with pytest.raises(UnsupportedBagError, match=r"^.*cdr\.mcap: /x holds ROS 2 CDR .*\.bag"):
        recover(src, tmp_path / "out.bag")
    assert not (tmp_path / "out.bag").exists()
    recover(src, tmp_path / "out.mcap")
    with McapReader(tmp_path / "out.mcap") as reader:
        assert reader.profile == "ros2"
        assert [c.topic for c in reader.connections] == ["/x"]


def test_the_report_says_what_was_recovered_and_how(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.bag", 10, close=False)
    with open_writer(tmp_path / "quiet.bag") as writer:  # a connection with no messages
        writer.add_connection("/quiet", "std_msgs/String", STRING_MD5, "string data\n")
    out = tmp_path / "y.bag"
    report = recover(sample.path, out)
    with open_bag(sample.path) as reader:
        notes = tuple(reader.notes)
    assert notes  # an unclosed recording is read by walking it, and says so
    assert (report.source, report.output, report.connections, report.notes) == (
        sample.path,
        out,
        4,
        notes,
    )
    # rosbag reindex keeps every connection, whether or not it has messages
    recover(tmp_path / "quiet.bag", tmp_path / "quiet2.bag")
    assert [c.topic for c in bag_info(tmp_path / "quiet2.bag").connections] == ["/quiet"]


def test_recover_never_overwrites_unless_asked(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.bag", 10)
    with pytest.raises(BagUsageError, match=r"x\.bag into itself; give another output file"):
        recover(sample.path, sample.path, overwrite=True)
    other = write_sample(tmp_path / "y.bag", 3).path
    with pytest.raises(BagUsageError, match="exists; refusing to overwrite it"):
        recover(sample.path, other)
    assert recover(sample.path, other, overwrite=True).messages == 10


def test_lost_data_is_one_line_naming_each_loss(tmp_path: Path) -> None:
    report = RecoverReport(
        tmp_path / "a.bag", tmp_path / "b.bag", "bag", False, 1, 1, (), ("one", "two")
    )
    with pytest.raises(DataLossError) as err:
        report.raise_if_lost()
    assert (
        str(err.value) == f"recovered 1 message into {tmp_path / 'b.bag'}, but lost data: one; two"
    )
