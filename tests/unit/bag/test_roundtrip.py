"""Our writers and readers together, for both formats: streams, info, filters, layout."""

from __future__ import annotations

import struct
from pathlib import Path

import pytest

from rostools.bag.formats import rosbag1_format as bagfmt
from rostools.bag.formats.access import bag_info, open_bag, open_writer
from rostools.bag.formats.model import BagUsageError, UnsupportedBagError
from rostools.errors import UsageError
from tests.support.bagdata import SAMPLE_CONNECTIONS, STEP_NS, read_stream, write_sample

CASES = [
    ("x.bag", "none"),
    ("x.bag", "bz2"),
    ("x.bag", "lz4"),
    ("x.mcap", "zstd"),
    ("x.mcap", "lz4"),
    ("x.mcap", "none"),
]


@pytest.mark.parametrize(("name", "compression"), CASES)
@pytest.mark.parametrize("chunk_size", [1, 3000, None])
def test_stream_round_trip(
    tmp_path: Path, name: str, compression: str, chunk_size: int | None
) -> None:
    sample = write_sample(tmp_path / name, 500, compression=compression, chunk_size=chunk_size)
    assert read_stream(sample.path) == sample.stream


@pytest.mark.parametrize(("name", "compression"), CASES)
def test_info(tmp_path: Path, name: str, compression: str) -> None:
    sample = write_sample(tmp_path / name, 400, compression=compression, chunk_size=4000)
    info = bag_info(sample.path)
    assert info.format == ("mcap" if name.endswith(".mcap") else "bag")
    assert info.indexed
    assert info.message_count == 400
    assert info.start_ns == 0
    assert info.end_ns == 399 * STEP_NS
    assert info.duration_ns == 399 * STEP_NS
    assert info.size == sample.path.stat().st_size
    assert [c.compression for c in info.compression] == [compression]
    assert info.compression[0].chunks == info.chunk_count > 1
    chatter = next(t for t in info.topics if t.topic == "/chatter")
    assert (chatter.messages, chatter.connections, chatter.type) == (200, 2, "std_msgs/String")
    assert [t.topic for t in info.topics] == ["/chatter", "/count", "/point"]
    assert info.types["geometry_msgs/Point"] == SAMPLE_CONNECTIONS[3][2]
    assert sum(info.connection_counts.values()) == 400
    if compression == "none":
        assert info.compressed_size == info.uncompressed_size
    else:
        assert info.compressed_size < info.uncompressed_size


@pytest.mark.parametrize("name", ["x.bag", "x.mcap"])
def test_connections_keep_their_headers(tmp_path: Path, name: str) -> None:
    sample = write_sample(tmp_path / name, 10)
    with open_bag(sample.path) as reader:
        conns = sorted(reader.connections, key=lambda c: c.id)
    assert [
        (c.id, c.topic, c.type, c.md5sum, c.definition, c.callerid, c.latching) for c in conns
    ] == [(i, *spec) for i, spec in enumerate(SAMPLE_CONNECTIONS)]


@pytest.mark.parametrize("name", ["x.bag", "x.mcap"])
def test_filters(tmp_path: Path, name: str) -> None:
    sample = write_sample(tmp_path / name, 300, chunk_size=2000)
    stream = sample.stream
    assert read_stream(sample.path, topics=["/count"]) == [m for m in stream if m[0] == "/count"]
    lo, hi = 10 * STEP_NS, 20 * STEP_NS
    assert read_stream(sample.path, start=lo, end=hi) == [m for m in stream if lo <= m[2] <= hi]
    assert read_stream(sample.path, start=0, end=0) == stream[:1]  # 0 is a time, inclusive
    with open_bag(sample.path) as reader:
        second = [c for c in reader.connections if c.callerid == "/talker2"]
        got = [(c.callerid, bytes(d)) for c, _, d in reader.messages(connections=second)]
    assert got == [(m[1], m[3]) for m in stream if m[1] == "/talker2"]
    assert read_stream(sample.path, topics=["/nothing"]) == []


@pytest.mark.parametrize("name", ["x.bag", "x.mcap"])
def test_out_of_order_writes_read_in_time_order(tmp_path: Path, name: str) -> None:
    writer = open_writer(tmp_path / name, chunk_size=200)
    conn = writer.add_connection(
        "/t", "std_msgs/Int32", "da5909fbe378aeaf85e547e830cc1bb7", "int32 data\n"
    )
    times = [50, 10, 40, 0, 30, 20, 5, 45] * 20
    for i, t in enumerate(times):
        writer.write(conn, t * 1_000_000_000 + i, struct.pack("<i", i))
    writer.close()
    got = [t for _, t, _ in open_bag(tmp_path / name).messages()]
    assert got == sorted(t * 1_000_000_000 + i for i, t in enumerate(times))


@pytest.mark.parametrize("name", ["x.bag", "x.mcap"])
def test_empty_definition_reads_raw(tmp_path: Path, name: str) -> None:
    writer = open_writer(tmp_path / name)
    conn = writer.add_connection("/e", "custom_msgs/Thing", "0123456789abcdef0123456789abcdef", "")
    writer.write(conn, 0, b"\x01\x02")
    writer.close()
    with open_bag(tmp_path / name) as reader:
        ((c, t, data),) = list(reader.messages())
    assert (c.definition, c.md5sum, t, bytes(data)) == (
        "",
        "0123456789abcdef0123456789abcdef",
        0,
        b"\x01\x02",
    )


@pytest.mark.parametrize("name", ["x.bag", "x.mcap"])
def test_empty_bag(tmp_path: Path, name: str) -> None:
    writer = open_writer(tmp_path / name)
    writer.add_connection("/unused", "std_msgs/Empty", "d41d8cd98f00b204e9800998ecf8427e", "")
    writer.close()
    info = bag_info(tmp_path / name)
    assert (info.message_count, info.start_ns, info.end_ns, info.chunk_count) == (0, None, None, 0)
    assert read_stream(tmp_path / name) == []


def test_bag_layout_matches_rosbag(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.bag", 50)
    raw = sample.path.read_bytes()
    assert raw.startswith(bagfmt.MAGIC)
    fields, start, length = bagfmt.read_record(raw, 13, len(raw))
    assert start + length == 4117  # 4104-byte header record: rosbag reindex rewrites it in place
    assert raw[start : start + length] == b" " * length
    assert bagfmt.u32_field(fields, "chunk_count") == 1
    assert bagfmt.u32_field(fields, "conn_count") == 4
    chunk, _, _ = bagfmt.read_record(raw, 4117, len(raw))
    assert bagfmt.op_of(chunk) == bagfmt.OP_CHUNK
    index_pos = bagfmt.u64_field(fields, "index_pos")
    conn, _, _ = bagfmt.read_record(raw, index_pos, len(raw))
    assert bagfmt.op_of(conn) == bagfmt.OP_CONNECTION


def test_unclosed_bag_keeps_the_open_chunk(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.bag", 300, chunk_size=5000, close=False)
    with open_bag(sample.path) as reader:
        assert not reader.indexed
        assert reader.notes
        assert not reader.damage
        got = [(c.topic, c.callerid, t, bytes(d)) for c, t, d in reader.messages()]
        assert reader.info().message_count == 300
    assert got == sample.stream


def test_writer_misuse(tmp_path: Path) -> None:
    path = tmp_path / "x.bag"
    writer = open_writer(path)
    conn = writer.add_connection("/t", "std_msgs/Empty", "d41d8cd98f00b204e9800998ecf8427e", "")
    other = open_writer(tmp_path / "y.bag").add_connection(
        "/u", "std_msgs/Empty", "d41d8cd98f00b204e9800998ecf8427e", ""
    )
    with pytest.raises(BagUsageError):
        writer.write(other, 0, b"")
    with pytest.raises(BagUsageError):
        writer.write(conn, -1, b"")
    with pytest.raises(BagUsageError):
        writer.write(conn, 1 << 32 << 30, b"")
    writer.close()
    with pytest.raises(UsageError):
        writer.write(conn, 0, b"")
    with pytest.raises(BagUsageError, match="exists"):
        open_writer(path)


def test_writer_choices(tmp_path: Path) -> None:
    with pytest.raises(BagUsageError, match="zstd"):
        open_writer(tmp_path / "x.bag", compression="zstd")
    with pytest.raises(BagUsageError, match="bz2"):
        open_writer(tmp_path / "x.mcap", compression="bz2")
    with pytest.raises(BagUsageError):
        open_writer(tmp_path / "x.bag", format="db3")
    writer = open_writer(tmp_path / "named.bag", format="mcap")
    writer.close()
    assert (tmp_path / "named.bag").read_bytes().startswith(b"\x89MCAP0\r\n")
    with pytest.raises(UnsupportedBagError):
        from rostools.bag.formats.rosbag1_writer import Bag1Writer

        Bag1Writer(tmp_path / "z.bag", compression="gzip")


@pytest.mark.parametrize("name", ["x.bag", "x.mcap"])
def test_abort_and_exceptions_delete_the_file(tmp_path: Path, name: str) -> None:
    path = tmp_path / name
    with pytest.raises(RuntimeError), open_writer(path) as writer:
        conn = writer.add_connection("/t", "std_msgs/Empty", "d41d8cd98f00b204e9800998ecf8427e", "")
        writer.write(conn, 0, b"")
        raise RuntimeError("boom")
    assert not path.exists()


@pytest.mark.parametrize("name", ["x.bag", "x.mcap"])
def test_times_and_frequencies(tmp_path: Path, name: str) -> None:
    from rostools.bag.formats.access import topic_frequencies

    sample = write_sample(tmp_path / name, 401, chunk_size=3000)
    with open_bag(sample.path) as reader:
        times = [(c.id, t) for c, t, _ in reader.times()]
        assert times == [(c.id, t) for c, t, _ in reader.messages()]
        rates = topic_frequencies(reader)
    assert rates["/count"] == pytest.approx(1e9 / (4 * STEP_NS))
    assert rates["/chatter"] == pytest.approx(1e9 / (2 * STEP_NS))  # gaps of 1 and 3 steps


@pytest.mark.parametrize("name", ["x.bag", "x.mcap"])
def test_connection_for_publisher_headers(tmp_path: Path, name: str) -> None:
    writer = open_writer(tmp_path / name)
    base = {
        "topic": "/chatter",
        "type": "std_msgs/String",
        "md5sum": "992ce8a1687cec8c8bd883ec73ca41d1",
        "message_definition": "string data\n",
        "callerid": "/talker",
        "latching": "1",
    }
    first = writer.connection_for("/chatter", base)
    again = writer.connection_for("/chatter", dict(base))
    other = writer.connection_for("/chatter", {**base, "callerid": "/talker2", "latching": "0"})
    assert first is again
    assert other.id != first.id
    assert (first.callerid, first.latching, other.latching) == ("/talker", True, False)
    writer.write(first, 1, b"\x01\x00\x00\x00a")
    writer.write(other, 2, b"\x01\x00\x00\x00b")
    writer.close()
    with open_bag(tmp_path / name) as reader:
        assert [c.header() for c in reader.connections] == [
            base,
            {**base, "callerid": "/talker2", "latching": "0"},
        ]
