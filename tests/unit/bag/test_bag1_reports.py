"""What the ``.bag`` reader says about a file: its errors, notes and damage, word for word.

Positions and counts come from the layout of the rosbag v2.0 format
(http://wiki.ros.org/Bags/Format/2.0), read from the test file with ``bag_records``.
"""

from __future__ import annotations

import re
import struct
from pathlib import Path

import pytest

from rostools.bag.formats import rosbag1_format as fmt
from rostools.bag.formats.access import open_writer
from rostools.bag.formats.model import BagFormatError, UnsupportedBagError
from rostools.bag.formats.rosbag1_reader import Bag1Reader
from rostools.wire.header import encode_fields
from tests.support.bagdata import (
    STRING_MD5,
    bag_chunk,
    bag_connection,
    bag_message,
    bag_records,
    chunk_spans,
    handmade_bag,
    read_stream,
    write_late_chunk,
    write_sample,
)


def _with_bag_header(raw: bytes, **fields: bytes | None) -> bytes:
    """``raw`` with bag header fields changed (None drops one), kept at rosbag's 4096 bytes."""
    [(_, _, old, _, _)] = bag_records(raw, 13, fmt.FIRST_RECORD_POS)
    new = {**old, **fields}
    header = fmt.encode_header({k: v for k, v in new.items() if v is not None})
    padding = b" " * (fmt.BAG_HEADER_SPACE - len(header))
    record = struct.pack("<I", len(header)) + header + struct.pack("<I", len(padding)) + padding
    return raw[:13] + record + raw[fmt.FIRST_RECORD_POS :]


def _index_pos(raw: bytes) -> int:
    [(_, _, fields, _, _)] = bag_records(raw, 13, fmt.FIRST_RECORD_POS)
    return fmt.u64_field(fields, "index_pos")


@pytest.mark.parametrize(
    ("head", "error", "said"),
    [
        (b"#ROSBAG V1.2\nold", UnsupportedBagError, "is a rosbag of version 1.2; only 2.0 is read"),
        (b"#ROSBAG V\xff.0\nxx", UnsupportedBagError, "is a rosbag of version \ufffd.0; only"),
        (b"SQLite format 3\x00", BagFormatError, "is an SQLite database (a ROS 2 bag?), not a"),
        (b"a text file, not a bag", BagFormatError, "is not a ROS 1 bag (no '#ROSBAG V2.0' line)"),
        (b"", BagFormatError, "is empty, not a bag"),
    ],
)
def test_what_is_not_a_v2_bag_is_named(
    tmp_path: Path, head: bytes, error: type[Exception], said: str
) -> None:
    path = tmp_path / "x.bag"
    path.write_bytes(head)
    with pytest.raises(error) as err:
        Bag1Reader(path)
    assert str(err.value).startswith(f"{path} {said}")


def test_a_bag_header_that_is_not_one(tmp_path: Path) -> None:
    raw = write_sample(tmp_path / "x.bag", 5).path.read_bytes()
    bad = tmp_path / "bad.bag"
    bad.write_bytes(_with_bag_header(raw, op=bytes([fmt.OP_CHUNK])))
    with pytest.raises(BagFormatError) as err:
        Bag1Reader(bad)
    assert str(err.value) == f"{bad}: damaged bag header (the first record is not a bag header)"
    bad.write_bytes(_with_bag_header(raw, encryptor=b"rosbag/AesCbcEncryptor"))
    with pytest.raises(UnsupportedBagError) as err:
        Bag1Reader(bad)
    assert str(err.value) == f"{bad} is encrypted (rosbag encrypt); decrypt it first"


def test_why_a_bag_is_read_without_its_index(tmp_path: Path) -> None:
    raw = write_sample(tmp_path / "x.bag", 40, chunk_size=2000).path.read_bytes()
    index_pos = _index_pos(raw)
    bad = tmp_path / "bad.bag"
    scanning = "; read by scanning its chunks"

    def unindexed(data: bytes) -> str | None:
        bad.write_bytes(data)
        with Bag1Reader(bad) as reader:
            assert [m[2] for m in read_stream(bad)] == [
                m[2] for m in read_stream(tmp_path / "x.bag")
            ]
            return reader.unindexed

    # rosbag writes index_pos 0 until it closes the file (or none at all, some writers)
    assert unindexed(_with_bag_header(raw, index_pos=struct.pack("<Q", 0))) == (
        "unindexed: an unclosed recording" + scanning
    )
    assert unindexed(_with_bag_header(raw, index_pos=None)) == (
        "unindexed: an unclosed recording" + scanning
    )
    assert unindexed(raw[: index_pos - 1]) == (
        f"unindexed: cut short (its index at {index_pos} is past the end, {index_pos - 1} bytes)"
        + scanning
    )
    found = unindexed(raw[:index_pos])  # the index would start at the very end
    assert found is not None and found.startswith(
        f"unindexed: its index at {index_pos} is damaged ("
    )
    assert found.endswith(scanning)
    broken = bytearray(raw)
    broken[index_pos + 4 : index_pos + 8] = b"\xff\xff\xff\x7f"  # its first record's header
    found = unindexed(bytes(broken))
    assert found is not None and found.startswith(
        f"unindexed: its index at {index_pos} is damaged ("
    )


def test_an_empty_bag_is_an_indexed_bag(tmp_path: Path) -> None:
    # rosbag writes the index of a bag without messages right after the bag header
    with open_writer(tmp_path / "empty.bag"):
        pass
    raw = (tmp_path / "empty.bag").read_bytes()
    assert _index_pos(raw) == len(raw) == fmt.FIRST_RECORD_POS
    with Bag1Reader(tmp_path / "empty.bag") as reader:
        assert reader.indexed and reader.info().message_count == 0
    # unclosed, it has nothing to read at all
    (tmp_path / "open.bag").write_bytes(_with_bag_header(raw, index_pos=struct.pack("<Q", 0)))
    with pytest.raises(BagFormatError) as err:
        Bag1Reader(tmp_path / "open.bag")
    assert str(err.value) == (
        f"{tmp_path / 'open.bag'}: unindexed bag that ends after its header (no chunks, no index)"
    )
    (tmp_path / "junk.bag").write_bytes((tmp_path / "open.bag").read_bytes() + b"junk" * 10)
    with pytest.raises(BagFormatError) as err:
        Bag1Reader(tmp_path / "junk.bag")
    assert str(err.value) == (
        f"{tmp_path / 'junk.bag'}: unindexed bag with nothing readable after its header"
    )


def test_records_out_of_time_order_are_counted_per_chunk(tmp_path: Path) -> None:
    path = tmp_path / "x.bag"
    write_late_chunk(path)
    chunks = [r[0] for r in bag_records(path.read_bytes()) if r[1] == fmt.OP_CHUNK]
    with Bag1Reader(path) as reader:
        assert reader.order_notes() == [f"chunk at {chunks[0]}: 2 messages out of time order"]
    with open_writer(tmp_path / "one.bag") as writer:
        conn = writer.add_connection("/t", "std_msgs/String", STRING_MD5, "string data\n")
        for t in (2, 1):
            writer.write(conn, t, struct.pack("<I", 0))
    with Bag1Reader(tmp_path / "one.bag") as reader:
        assert reader.order_notes() == [
            f"chunk at {fmt.FIRST_RECORD_POS}: 1 message out of time order"
        ]


def test_header_text_that_is_not_utf8_is_read_with_replacement(tmp_path: Path) -> None:
    raw = write_sample(tmp_path / "x.bag", 8).path.read_bytes()
    bad = tmp_path / "bad.bag"
    bad.write_bytes(raw.replace(b"/chatter", b"/ch\xfftter").replace(b"/talker2", b"/t\xfflker2"))
    with Bag1Reader(bad) as reader:
        assert {c.topic for c in reader.connections} >= {"/ch\ufffdtter"}
        assert "/t\ufffdlker2" in {c.callerid for c in reader.connections}


def _mapped(path: Path) -> int:
    return Path("/proc/self/maps").read_text().count(str(path))


def test_closing_unmaps_the_file(tmp_path: Path) -> None:
    path = write_sample(tmp_path / "x.bag", 5).path
    reader = Bag1Reader(path)
    info = reader.info()
    assert (info.path, info.version, info.connections) == (path, "2.0", tuple(reader.connections))
    assert _mapped(path) == 1
    reader.close()
    assert _mapped(path) == 0


def test_damage_is_said_where_it_is(tmp_path: Path) -> None:
    raw = write_sample(tmp_path / "x.bag", 300, chunk_size=3000).path.read_bytes()
    chunks = [r for r in bag_records(raw) if r[1] == fmt.OP_CHUNK]
    bad = tmp_path / "bad.bag"
    # junk in place of the third chunk's header: read on at the next record after it
    victim, after = chunks[2], chunks[2][3]
    bad.write_bytes(raw[: victim[0]] + b"\xee" * (after - victim[0]) + raw[after:])
    with Bag1Reader(bad) as reader:
        list(reader.messages())
        said = [d for d in reader.damage if d.startswith(f"{after - victim[0]} bytes at")]
    assert re.fullmatch(
        rf"{after - victim[0]} bytes at {victim[0]} do not parse \(.*\)"
        rf"; the index lists {_listed(raw, victim[0])} messages in chunks there"
        rf"; read on at {after}",
        said[0],
    ), reader.damage


def _listed(raw: bytes, chunk_pos: int) -> int:
    """The messages the chunk info of the chunk at ``chunk_pos`` lists."""
    for _, op, fields, data, dlen in bag_records(raw):
        if op == fmt.OP_CHUNK_INFO and fmt.u64_field(fields, "chunk_pos") == chunk_pos:
            return sum(struct.unpack_from(f"<{dlen // 4}I", raw, data)[1::2])
    raise AssertionError(f"no chunk info for {chunk_pos}")


def _chunk_infos(raw: bytes) -> list[tuple[int, dict[str, bytes], int, int]]:
    """(record position, fields, data start, data length) of each CHUNK_INFO record."""
    return [(r[0], r[2], r[3], r[4]) for r in bag_records(raw) if r[1] == fmt.OP_CHUNK_INFO]


def _times(fields: dict[str, bytes]) -> tuple[int, int]:
    return fmt.time_field(fields, "start_time"), fmt.time_field(fields, "end_time")


def test_chunk_info_times_that_disagree_with_the_records_are_noted(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.bag", 200, chunk_size=3000)
    raw = sample.path.read_bytes()
    pos, fields, data, dlen = _chunk_infos(raw)[1]
    chunk_pos = fmt.u64_field(fields, "chunk_pos")
    start, end = _times(fields)  # the first and last record's times (the format's rule)
    bad = tmp_path / "bad.bag"
    for new_start, new_end in ((start, end + 10**9), (start + 1, end)):
        changed = {**fields, "start_time": fmt.pack_time(new_start)}
        changed["end_time"] = fmt.pack_time(new_end)
        record = fmt.encode_record(changed, raw[data : data + dlen])
        bad.write_bytes(raw[:pos] + record + raw[pos + len(record) :])
        with Bag1Reader(bad) as reader:
            assert [m[2] for m in read_stream(bad)] == [m[2] for m in sample.stream]
            list(reader.messages())
            assert reader.notes == [
                f"chunk at {chunk_pos}: its records run from {start} to {end} ns,"
                f" its chunk info says {new_start} to {new_end}"
            ]
    # a read of some topics only: records inside the chunk info's times are no news
    bad.write_bytes(raw[:pos] + record + raw[pos + len(record) :])
    with Bag1Reader(bad) as reader:
        list(reader.messages(topics=["/point"]))
        assert reader.notes == []


#: What reading a run of 0xee bytes as a record header says (its length reads as 0xeeeeeeee).
JUNK = "record header at {} (4008636142 bytes) is cut short or corrupt"


def _read(reader: Bag1Reader, **kwargs: object) -> list[tuple[str, int]]:
    return [(c.topic, t) for c, t, _ in reader.messages(**kwargs)]  # type: ignore[arg-type]


def test_a_bag_header_without_its_counts_is_read_unindexed(tmp_path: Path) -> None:
    # rosbag.Bag calls such a bag unindexed: without the counts the index cannot be read
    sample = write_sample(tmp_path / "x.bag", 40, chunk_size=2000)
    raw = sample.path.read_bytes()
    bad = tmp_path / "bad.bag"
    for name in ("conn_count", "chunk_count"):
        bad.write_bytes(_with_bag_header(raw, **{name: None}))
        with Bag1Reader(bad) as reader:
            assert reader.unindexed == (
                f"unindexed: its index at {_index_pos(raw)} is damaged (record header field"
                f" {name!r} is missing or not 4 bytes); read by scanning its chunks"
            )
            assert read_stream(bad) == sample.stream


def test_damaged_index_records_are_named(tmp_path: Path) -> None:
    raw = write_sample(tmp_path / "x.bag", 40, chunk_size=2000).path.read_bytes()
    index_pos = _index_pos(raw)
    conns = [r for r in bag_records(raw) if r[1] == fmt.OP_CONNECTION and r[0] >= index_pos]
    info_pos, fields, data, dlen = _chunk_infos(raw)[0]
    bad = tmp_path / "bad.bag"

    def why(data: bytes) -> str | None:
        bad.write_bytes(data)
        with Bag1Reader(bad) as reader:
            assert reader.connections and reader.chunks
            return reader.unindexed

    def damaged(detail: str) -> str:
        return (
            f"unindexed: its index at {index_pos} is damaged ({detail});"
            " read by scanning its chunks"
        )

    assert why(_with_bag_header(raw, conn_count=struct.pack("<I", 5))) == damaged(
        f"expected a connection record at {info_pos}"
    )
    assert why(_with_bag_header(raw, conn_count=struct.pack("<I", 3))) == damaged(
        f"expected a chunk info record at {conns[3][0]}"
    )
    count_at = info_pos + raw[info_pos:data].index(b"count=") + len(b"count=")
    more = raw[:count_at] + struct.pack("<I", dlen // 8 + 1) + raw[count_at + 4 :]
    assert why(more) == damaged(
        f"chunk info at {info_pos} lists {dlen // 8 + 1} connections in {dlen} B"
    )
    chunk_pos = fmt.u64_field(fields, "chunk_pos")
    stranger = raw[:data] + struct.pack("<I", 9) + raw[data + 4 :]
    assert why(stranger) == damaged(
        f"the chunk info of the chunk at {chunk_pos} lists connection 9, which no connection"
        " record defines"
    )
    at = info_pos + raw[info_pos:data].index(b"chunk_pos=") + len(b"chunk_pos=")
    elsewhere = raw[:at] + struct.pack("<Q", conns[0][0]) + raw[at + 8 :]
    assert why(elsewhere) == damaged(f"chunk info points at {conns[0][0]}, which is not a chunk")


def test_a_connection_record_without_its_topic_field(tmp_path: Path) -> None:
    # The connection header in the record's data names the topic too (Bags/Format/2.0).
    nameless = fmt.encode_record(
        {"op": bytes([fmt.OP_CONNECTION]), "conn": struct.pack("<I", 1)},
        encode_fields({"type": "std_msgs/String", "md5sum": STRING_MD5}),
    )
    records = bag_connection(0, "/t", in_record=False) + nameless
    records += bag_message(0, 5, b"a") + bag_message(1, 6, b"b")
    path = handmade_bag(tmp_path / "x.bag", bag_chunk(records))
    with Bag1Reader(path) as reader:
        assert [(c.id, c.topic) for c in reader.connections] == [(0, "/t"), (1, "")]
        assert _read(reader) == [("/t", 5), ("", 6)]


def test_the_index_repeats_connections_once(tmp_path: Path) -> None:
    raw = write_sample(tmp_path / "x.bag", 40, chunk_size=2000).path.read_bytes()
    bad = tmp_path / "bad.bag"
    # scanned, the records in the chunks and in the index both define each connection
    bad.write_bytes(_with_bag_header(raw, index_pos=struct.pack("<Q", 0)))
    with Bag1Reader(bad) as reader:
        assert [c.id for c in reader.connections] == [0, 1, 2, 3]


def _data_pos(raw: bytes, pos: int) -> int:
    """Where the data of the record at ``pos`` starts."""
    return pos + 8 + int(struct.unpack_from("<I", raw, pos)[0])


def test_a_chunk_header_without_compression_is_uncompressed(tmp_path: Path) -> None:
    first = bag_chunk(bag_connection(0, "/t") + bag_message(0, 1) + bag_message(0, 2), None)
    last = bag_message(0, 5, b"cut")
    second = bag_chunk(bag_message(0, 3) + bag_message(0, 4) + last, None)
    path = handmade_bag(tmp_path / "x.bag", first + second[:-2])
    raw = path.read_bytes()
    pos = fmt.FIRST_RECORD_POS + len(first)
    data = _data_pos(raw, pos)
    with Bag1Reader(path) as reader:
        assert _read(reader) == [("/t", 1), ("/t", 2), ("/t", 3), ("/t", 4)]
        assert [c.compression for c in reader.chunks] == ["none", "none"]
        assert reader.damage == [
            f"chunk at {pos} ends in a partial record ({len(last) - 2} bytes lost)",
            f"chunk at {pos} is cut short ({len(raw) - data} of its bytes are in the file);"
            " 2 messages salvaged from it",
        ]


def test_a_chunk_cut_after_its_header(tmp_path: Path) -> None:
    first = bag_chunk(bag_connection(0, "/t") + bag_message(0, 1))
    second = bag_chunk(bag_message(0, 3))
    head = _data_pos(second, 0)
    path = handmade_bag(tmp_path / "x.bag", first + second[:head])
    with Bag1Reader(path) as reader:
        assert _read(reader) == [("/t", 1)]
        assert reader.damage == [
            f"chunk at {fmt.FIRST_RECORD_POS + len(first)} is cut short (0 of its bytes are in"
            " the file); 0 messages salvaged from it"
        ]


def test_a_chunk_longer_than_the_file_is_read_up_to_the_next_record(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.bag", 300, chunk_size=3000)
    raw = sample.path.read_bytes()
    records = bag_records(raw)
    pos, _, _, data, dlen = [r for r in records if r[1] == fmt.OP_CHUNK][1]
    inside = [r for r in bag_records(raw, data, data + dlen) if r[1] == fmt.OP_MSG_DATA]
    bad = tmp_path / "bad.bag"
    bad.write_bytes(raw[: data - 4] + struct.pack("<I", 2**31 - 1) + raw[data:])
    with Bag1Reader(bad) as reader:
        assert read_stream(bad) == sample.stream
        assert reader.damage == [
            f"chunk at {pos} does not fit its record (record data at {pos} (2147483647 bytes)"
            f" is cut short); {len(inside)} messages salvaged from it, read on at {data + dlen}"
        ]


def test_junk_in_place_of_a_chunk_names_what_the_index_lists_there(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.bag", 300, chunk_size=3000)
    raw = sample.path.read_bytes()
    (start, end), after = chunk_spans(raw)[1], chunk_spans(raw)[2][0]
    assert end == after
    bad = tmp_path / "bad.bag"
    bad.write_bytes(raw[:start] + b"\xee" * (end - start) + raw[end:])
    with Bag1Reader(bad) as reader:
        list(reader.messages())
        assert reader.damage == [
            f"{end - start} bytes at {start} do not parse ({JUNK.format(start)}); the index"
            f" lists {_listed(raw, start)} messages in chunks there; read on at {end}"
        ]


def test_junk_between_and_after_chunks_in_an_unclosed_bag(tmp_path: Path) -> None:
    first = bag_chunk(bag_connection(0, "/t") + bag_message(0, 1))
    second = bag_chunk(bag_message(0, 2) + bag_message(0, 3)) + bag_chunk(bag_message(0, 4))
    path = handmade_bag(tmp_path / "x.bag", first + b"\xee" * 10 + second + b"\xee" * 6)
    junk = fmt.FIRST_RECORD_POS + len(first)
    tail = junk + 10 + len(second)
    with Bag1Reader(path) as reader:
        assert _read(reader) == [("/t", 1), ("/t", 2), ("/t", 3), ("/t", 4)]
        assert reader.damage == [
            f"10 bytes at {junk} do not parse ({JUNK.format(junk)}); read on at {junk + 10}",
            f"6 bytes at {tail} do not parse ({JUNK.format(tail)})",
        ]


def test_message_records_outside_any_chunk(tmp_path: Path) -> None:
    loose = bag_message(0, 2) + bag_message(0, 3)
    chunk = bag_chunk(bag_message(0, 4))
    path = handmade_bag(tmp_path / "x.bag", bag_connection(0, "/t") + loose + chunk)
    pos = fmt.FIRST_RECORD_POS + len(bag_connection(0, "/t"))
    with Bag1Reader(path) as reader:
        assert _read(reader) == [("/t", 2), ("/t", 3), ("/t", 4)]
        assert reader.notes[1:] == [
            f"2 message records at {pos} lie outside any chunk; read them as they are"
        ]
        assert reader.damage == []


def test_damage_inside_chunks_is_said_where_it_is(tmp_path: Path) -> None:
    bad_header = fmt.encode_record(
        {"op": bytes([fmt.OP_CONNECTION]), "conn": struct.pack("<I", 7), "topic": b"/x"},
        b"\xff\xff\xff\x7f",
    )
    head = bag_connection(1, "/u") + bag_connection(0, "/t") + bag_message(0, 1)
    head += bag_message(5, 1)
    first = bag_chunk(head + b"\xee" * 10 + bag_message(0, 2) + bag_message(0, 3))
    second = bag_chunk(bad_header + bag_message(0, 4) + b"\xee" * 5)
    partial = bag_message(0, 7)
    unclosed = fmt.encode_record(
        {"op": bytes([fmt.OP_CHUNK]), "compression": b"none", "size": struct.pack("<I", 0)}
    )
    unclosed += bag_message(0, 6) + partial[:-1]
    path = handmade_bag(tmp_path / "x.bag", bad_header + first + second + unclosed)
    raw = path.read_bytes()
    top = fmt.FIRST_RECORD_POS
    at = [top + len(bad_header)]
    at += [at[0] + len(first), at[0] + len(first) + len(second)]
    data = [_data_pos(raw, p) for p in at]
    junk = data[0] + len(head)
    tail = data[1] + len(bad_header) + len(bag_message(0, 4))
    with Bag1Reader(path) as reader:
        assert [c.id for c in reader.connections] == [0, 1]  # in id order, as an index lists them
        assert reader.info().message_count == 5  # the message of a lost connection left out
        assert _read(reader) == [("/t", t) for t in (1, 2, 3, 4, 6)]
        assert reader.order_notes() == []
        header_error = reader.damage[0].partition("malformed header: ")[2]
        assert reader.damage == [
            f"skipped a damaged connection record at {top}: connection 7 has a malformed"
            f" header: {header_error}",
            f"chunk at {at[0]}: 10 bytes at offset {junk - data[0]} do not parse"
            f" ({JUNK.format(junk)}); read on at offset {junk + 10 - data[0]}",
            f"chunk at {at[1]}: skipped a damaged connection record: connection 7 has a"
            f" malformed header: {header_error}",
            f"chunk at {at[1]}: record at {tail - data[1]}: {JUNK.format(tail)}",
            f"chunk at {at[2]} ends in a partial record ({len(partial) - 1} bytes lost)",
            f"chunk at {at[0]}: 1 message of connections whose record is lost",
        ]
        assert header_error


@pytest.mark.parametrize(("name", "said"), [(b"zip", "zip"), (b"zi\xff", "zi\ufffd")])
def test_unknown_compression_is_named(tmp_path: Path, name: bytes, said: str) -> None:
    odd = fmt.encode_record(
        {"op": bytes([fmt.OP_CHUNK]), "compression": name, "size": struct.pack("<I", 0)},
        bag_message(0, 1),
    )
    path = handmade_bag(
        tmp_path / "x.bag", bag_connection(0, "/t") + odd + bag_chunk(bag_message(0, 2))
    )
    pos = fmt.FIRST_RECORD_POS + len(bag_connection(0, "/t"))
    with Bag1Reader(path) as reader:
        assert _read(reader) == [("/t", 2)]
        assert reader.damage == [
            f"chunk at {pos} is unreadable: {path}: chunk at {pos} uses unknown compression"
            f" {said!r}"
        ]


def test_a_scanned_chunk_spans_its_records_times(tmp_path: Path) -> None:
    write_late_chunk(tmp_path / "x.bag")
    bad = tmp_path / "bad.bag"
    bad.write_bytes(
        _with_bag_header((tmp_path / "x.bag").read_bytes(), index_pos=struct.pack("<Q", 0))
    )
    with Bag1Reader(bad) as reader:
        assert [(c.start_ns, c.end_ns) for c in reader.chunks] == [(1, 11)]
        info = reader.info()
        assert (info.start_ns, info.end_ns, info.message_count) == (1, 11, 8)


def test_an_unreadable_chunk_is_named_among_the_order_notes(tmp_path: Path) -> None:
    path = tmp_path / "x.bag"
    with open_writer(path, compression="bz2", chunk_size=10**6) as writer:
        conn = writer.add_connection("/t", "std_msgs/String", STRING_MD5, "string data\n")
        for times in ((1, 2), (5, 3)):
            for t in times:
                writer.write(conn, t, struct.pack("<I", 0))
            writer.flush()
    raw = path.read_bytes()
    chunks = [r for r in bag_records(raw) if r[1] == fmt.OP_CHUNK]
    first_data = chunks[0][3]
    path.write_bytes(raw[:first_data] + b"\x00" * 10 + raw[first_data + 10 :])
    with Bag1Reader(path) as reader:
        notes = reader.order_notes()
    assert len(notes) == 2
    assert notes[0].startswith(f"chunk at {chunks[0][0]}: bz2 chunk does not decompress: ")
    assert notes[1] == f"chunk at {chunks[1][0]}: 1 message out of time order"


def test_index_records_with_a_count_unlike_their_length_are_skipped_by_count(
    tmp_path: Path,
) -> None:
    # rosbag reads `count` entries whatever data_len says; without a count, data_len says
    sample = write_sample(tmp_path / "x.bag", 40, chunk_size=2000)
    raw = _with_bag_header(sample.path.read_bytes(), index_pos=struct.pack("<Q", 0))
    index = [r for r in bag_records(raw) if r[1] == fmt.OP_INDEX_DATA]
    pos, _, fields, data, dlen = index[0]
    bad = tmp_path / "bad.bag"
    bad.write_bytes(raw[: data - 4] + struct.pack("<I", 0) + raw[data:])
    uncounted = fmt.encode_record(
        {k: v for k, v in fields.items() if k != "count"}, raw[data : data + dlen]
    )
    for damaged in (bad.read_bytes(), raw[:pos] + uncounted + raw[data + dlen :]):
        bad.write_bytes(damaged)
        with Bag1Reader(bad) as reader:
            assert read_stream(bad) == sample.stream
            assert reader.damage == [] and reader.notes == [reader.unindexed]


def _ranked(path: Path) -> Path:
    """/a (rank 0) at 5 and 6, /b (rank 1) at 0 and 6, in one chunk."""
    records = bag_connection(0, "/a") + bag_connection(1, "/b") + bag_message(1, 0)
    records += bag_message(0, 5) + bag_message(0, 6) + bag_message(1, 6)
    return handmade_bag(path, bag_chunk(records))


def test_a_read_between_times_keeps_its_bounds(tmp_path: Path) -> None:
    with Bag1Reader(_ranked(tmp_path / "x.bag")) as reader:
        assert _read(reader) == [("/b", 0), ("/a", 5), ("/a", 6), ("/b", 6)]
        assert _read(reader, start=1, end=5) == [("/a", 5)]
        assert _read(reader, start=6) == [("/a", 6), ("/b", 6)]


def test_times_of_some_topics(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.bag", 60, chunk_size=2000)
    count = [t for topic, _, t, _ in sample.stream if topic == "/count"]
    bad = tmp_path / "bad.bag"
    bad.write_bytes(_with_bag_header(sample.path.read_bytes(), index_pos=struct.pack("<Q", 0)))
    for path in (sample.path, bad):
        with Bag1Reader(path) as reader:
            assert [t for _, t, _ in reader.times(["/count"])] == count
            assert [t for _, t, _ in reader.times()] == [m[2] for m in sample.stream]
            wanted = reader.wanted(None, None)
            first = [t for _, t, _ in reader.chunk_messages(reader.chunks[0], wanted)]
            assert first[0] == 0


def test_index_records_that_do_not_parse_are_noted(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.bag", 40, chunk_size=2000)
    raw = sample.path.read_bytes()
    chunk = next(r for r in bag_records(raw) if r[1] == fmt.OP_CHUNK)
    pos, _, _, data, _ = next(r for r in bag_records(raw) if r[1] == fmt.OP_INDEX_DATA)
    ver = pos + raw[pos:data].index(b"ver=") + len(b"ver=")
    bad = tmp_path / "bad.bag"
    bad.write_bytes(raw[:ver] + struct.pack("<I", 2) + raw[ver + 4 :])
    said = (
        f"chunk at {chunk[0]}: its index disagrees with its records (its index records do not"
        f" parse: index data at {pos} has an unknown version); read from the records"
    )
    with Bag1Reader(bad) as reader:
        assert [t for _, t, _ in reader.times()] == [m[2] for m in sample.stream]
        assert reader.notes == [said]
        assert read_stream(bad) == sample.stream
    last, _, _, last_data, _ = [r for r in bag_records(raw) if r[1] == fmt.OP_INDEX_DATA][-1]
    count = last + raw[last:last_data].index(b"count=") + len(b"count=")
    bad.write_bytes(raw[:count] + struct.pack("<I", 2**31) + raw[count + 4 :])
    last_chunk = [r for r in bag_records(raw) if r[1] == fmt.OP_CHUNK][-1][0]
    with Bag1Reader(bad) as reader:
        list(reader.messages())
        assert reader.notes == [
            f"chunk at {last_chunk}: its index disagrees with its records (its index records do"
            f" not parse: index data at {last_data} is cut short); read from the records"
        ]
    op = pos + raw[pos:data].index(b"op=") + len(b"op=")
    bad.write_bytes(raw[:op] + bytes([fmt.OP_MSG_DATA]) + raw[op + 1 :])
    with Bag1Reader(bad) as reader:
        list(reader.messages())
        assert reader.notes == [
            said.replace(
                f"index data at {pos} has an unknown version", f"expected index data at {pos}"
            )
        ]


def test_a_message_of_an_unknown_connection_in_an_indexed_chunk(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.bag", 40, chunk_size=2000)
    raw = sample.path.read_bytes()
    chunk = next(r for r in bag_records(raw) if r[1] == fmt.OP_CHUNK)
    inner = bag_records(raw, chunk[3], chunk[3] + chunk[4])
    msg = next(r for r in inner if r[1] == fmt.OP_MSG_DATA and r[2]["conn"] == struct.pack("<I", 2))
    at = msg[0] + raw[msg[0] : msg[3]].index(b"conn=") + len(b"conn=")
    bad = tmp_path / "bad.bag"
    bad.write_bytes(raw[:at] + struct.pack("<I", 9) + raw[at + 4 :])
    lost = f"chunk at {chunk[0]}: 1 message of connections whose record is lost"
    t = fmt.time_field(msg[2], "time")
    with Bag1Reader(bad) as reader:
        assert _read(reader) == [(m[0], m[2]) for m in sample.stream if m[2] != t]
        assert reader.damage == [lost]
    with Bag1Reader(bad) as reader:  # read by walking, past records of other connections
        count = [m for m in sample.stream if m[0] == "/count" and m[2] != t]
        assert [(c.topic, t) for c, t, _ in reader.messages(topics=["/count"])] == [
            ("/count", m[2]) for m in count
        ]
        assert reader.damage == [lost]


def test_chunk_info_times_narrower_than_a_partial_read_are_noted(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.bag", 200, chunk_size=3000)
    raw = sample.path.read_bytes()
    pos, fields, data, dlen = _chunk_infos(raw)[1]
    chunk_pos = fmt.u64_field(fields, "chunk_pos")
    start, end = _times(fields)
    topic = next(m[0] for m in sample.stream if m[2] == end)
    first = min(m[2] for m in sample.stream if m[0] == topic and m[2] >= start)
    changed = {**fields, "end_time": fmt.pack_time(end - 1)}
    record = fmt.encode_record(changed, raw[data : data + dlen])
    bad = tmp_path / "bad.bag"
    bad.write_bytes(raw[:pos] + record + raw[pos + len(record) :])
    with Bag1Reader(bad) as reader:
        list(reader.messages(topics=[topic]))
        assert reader.notes == [
            f"chunk at {chunk_pos}: its records run from {first} to {end} ns,"
            f" its chunk info says {start} to {end - 1}"
        ]
