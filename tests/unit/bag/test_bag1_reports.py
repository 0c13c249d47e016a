"""What the ``.bag`` reader says about a file: its errors, notes and damage, word for word.

Positions and counts come from the layout of the rosbag v2.0 format
(http://wiki.ros.org/Bags/Format/2.0), read from the test file with ``bag_records``.
"""

from __future__ import annotations

import re
import struct
from pathlib import Path

import pytest

from rostools.bag import rosbag1_format as fmt
from rostools.bag.access import open_writer
from rostools.bag.model import BagFormatError, UnsupportedBagError
from rostools.bag.rosbag1_reader import Bag1Reader
from tests.support.bagdata import (
    STRING_MD5,
    bag_records,
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
