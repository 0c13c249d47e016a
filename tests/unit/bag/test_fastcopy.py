"""The chunk-for-chunk .bag -> MCAP path: same stream, valid indexes, fallbacks."""

from __future__ import annotations

import struct
from pathlib import Path

import pytest

from rostools.bag.formats import mcap_format as fmt
from rostools.bag.formats.access import open_writer
from rostools.bag.formats.base import Targets
from rostools.bag.formats.fastcopy import convert_chunks
from rostools.bag.formats.mcap_writer import McapWriter
from rostools.bag.formats.rosbag1_reader import Bag1Reader
from tests.support.bagdata import read_stream, write_sample


def fast_convert(src: Path, dst: Path) -> int | None:
    with Bag1Reader(src) as reader:
        writer = McapWriter(dst)
        targets = Targets(writer, reader.connections)
        done = convert_chunks(reader, writer, targets)
        if done is None:
            done = writer.write_many(reader.messages(), targets)
        writer.close()
    return done


def check_indexes(path: Path) -> int:
    """Every message index entry points at a message of its channel and time."""
    raw = path.read_bytes()
    checked = 0
    chunk: bytes | None = None
    for _, op, start, stop in fmt.records(raw, 8, len(raw)):
        record = fmt.parse(op, raw, start, stop)
        if isinstance(record, fmt.McapChunk):
            chunk = fmt.decompress(record.compression, record.records, record.uncompressed_size)
        elif isinstance(record, fmt.MessageIndex):
            assert chunk is not None
            for log_time, offset in record.records:
                opcode, _, channel, _, log, _ = fmt.MESSAGE_PREFIX.unpack_from(chunk, offset)
                assert (opcode, channel, log) == (fmt.OP_MESSAGE, record.channel_id, log_time)
                checked += 1
        elif op == fmt.OP_DATA_END:
            break
    return checked


@pytest.mark.parametrize("compression", ["none", "lz4", "bz2"])
def test_fast_path_keeps_the_stream(tmp_path: Path, compression: str) -> None:
    sample = write_sample(tmp_path / "x.bag", 2000, compression=compression, chunk_size=9000)
    assert fast_convert(sample.path, tmp_path / "x.mcap") == 2000
    assert read_stream(tmp_path / "x.mcap") == sample.stream
    assert check_indexes(tmp_path / "x.mcap") == 2000


def test_sequences_continue_across_chunks(tmp_path: Path) -> None:
    from mcap.reader import make_reader

    sample = write_sample(tmp_path / "x.bag", 400, chunk_size=2000)
    fast_convert(sample.path, tmp_path / "x.mcap")
    with (tmp_path / "x.mcap").open("rb") as f:
        seqs: dict[int, list[int]] = {}
        for _, channel, message in make_reader(f).iter_messages(log_time_order=True):
            seqs.setdefault(channel.id, []).append(message.sequence)
    assert all(s == list(range(len(s))) for s in seqs.values())


def test_out_of_order_chunk_takes_the_slow_path(tmp_path: Path) -> None:
    src = tmp_path / "x.bag"
    writer = open_writer(src, chunk_size=1000)
    conn = writer.add_connection(
        "/t", "std_msgs/Int32", "da5909fbe378aeaf85e547e830cc1bb7", "int32 data\n"
    )
    times = [i * 100 for i in range(60)]
    times[35], times[36] = times[36], times[35]  # one chunk holds a swapped pair
    for i, t in enumerate(times):
        writer.write(conn, t, struct.pack("<i", i))
    writer.close()
    slow: list[int] = []
    with Bag1Reader(src) as reader:
        original = reader.chunk_messages

        def spy(chunk, wanted):  # type: ignore[no-untyped-def]
            slow.append(chunk.pos)
            return original(chunk, wanted)

        reader.chunk_messages = spy  # type: ignore[method-assign]
        out = McapWriter(tmp_path / "x.mcap")
        assert convert_chunks(reader, out, Targets(out, reader.connections)) == 60
        out.close()
        assert len(slow) == 1 < len(reader.chunks)
    assert read_stream(tmp_path / "x.mcap") == read_stream(src)
    assert check_indexes(tmp_path / "x.mcap") == 60


def test_overlapping_chunks_are_not_fast(tmp_path: Path) -> None:
    src = tmp_path / "x.bag"
    writer = open_writer(src, chunk_size=300)
    conn = writer.add_connection(
        "/t", "std_msgs/Int32", "da5909fbe378aeaf85e547e830cc1bb7", "int32 data\n"
    )
    for i in range(100):
        writer.write(conn, (i % 50) * 1000 + i, struct.pack("<i", i))
    writer.close()
    with Bag1Reader(src) as reader:
        writer2 = McapWriter(tmp_path / "x.mcap")
        assert convert_chunks(reader, writer2, Targets(writer2, reader.connections)) is None
        writer2.abort()


def test_python_writer_header_order(tmp_path: Path) -> None:
    """rosbag's Python writer puts op first in message headers; the fast path reads both."""
    from rostools.bag.formats import rosbag1_format as bagfmt

    sample = write_sample(tmp_path / "x.bag", 300, compression="none")
    raw = bytearray(sample.path.read_bytes())
    cpp = b"\x09\x00\x00\x00conn="
    py_order = 0
    pos = raw.find(b"\x26\x00\x00\x00" + cpp)
    while pos >= 0:  # rewrite each 38-byte (conn, op, time) header as (op, conn, time)
        head = bytes(raw[pos + 4 : pos + 42])
        raw[pos + 4 : pos + 42] = head[13:21] + head[:13] + head[21:]
        py_order += 1
        pos = raw.find(b"\x26\x00\x00\x00" + cpp, pos + 42)
    assert py_order == 300
    (tmp_path / "py.bag").write_bytes(bytes(raw))
    assert bytes(raw[:13]) == bagfmt.MAGIC
    assert read_stream(tmp_path / "py.bag") == sample.stream
    assert fast_convert(tmp_path / "py.bag", tmp_path / "py.mcap") == 300
    assert read_stream(tmp_path / "py.mcap") == sample.stream
