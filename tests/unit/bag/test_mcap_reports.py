"""What the MCAP reader says about a file: its errors, notes and damage, word for word.

Positions come from the MCAP layout (https://mcap.dev/spec): magic, header, data section,
data end, summary, summary offsets, footer (its last 28 bytes before the closing magic).
"""

from __future__ import annotations

import struct
from pathlib import Path

import pytest

from rostools.bag.formats import mcap_format as fmt
from rostools.bag.formats.access import open_writer
from rostools.bag.formats.mcap_reader import McapReader
from rostools.bag.formats.model import BagFormatError
from tests.support.bagdata import (
    STRING_MD5,
    handmade_mcap,
    read_stream,
    write_late_chunk,
    write_sample,
)

#: The footer: opcode, length, summary start, summary offset start, summary CRC; then magic.
FOOTER = struct.Struct("<BQQQI")


def _footer(raw: bytes) -> tuple[int, int, int]:
    _, _, start, offsets, crc = FOOTER.unpack_from(raw, len(raw) - len(fmt.MAGIC) - FOOTER.size)
    return start, offsets, crc


def _with_footer(raw: bytes, start: int, offsets: int, crc: int) -> bytes:
    at = len(raw) - len(fmt.MAGIC) - FOOTER.size
    return raw[:at] + FOOTER.pack(fmt.OP_FOOTER, 20, start, offsets, crc) + fmt.MAGIC


@pytest.mark.parametrize(
    ("content", "said"),
    [
        (b"", "{path} is empty, not an MCAP file"),
        (b"#ROSBAG V2.0\n", "{path} is not an MCAP file (bad magic)"),
        (
            fmt.MAGIC + fmt.encode_data_end(),
            "{path}: MCAP file does not start with a header record",
        ),
    ],
)
def test_what_is_not_an_mcap_file_is_named(tmp_path: Path, content: bytes, said: str) -> None:
    path = tmp_path / "x.mcap"
    path.write_bytes(content)
    with pytest.raises(BagFormatError) as err:
        McapReader(path)
    assert str(err.value) == said.format(path=path)


def test_why_a_file_is_read_without_its_summary(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.mcap", 50, chunk_size=2000)
    raw = sample.path.read_bytes()
    start, offsets, crc = _footer(raw)
    bad = tmp_path / "bad.mcap"

    def read(data: bytes) -> McapReader:
        bad.write_bytes(data)
        with McapReader(bad) as reader:
            assert read_stream(bad) == sample.stream
            return reader

    scanning = "; read by scanning it"
    assert read(raw[:-1]).unindexed == "unindexed: no footer (unfinished or cut short)" + scanning
    assert read(_with_footer(raw, len(raw), offsets, 0)).unindexed == (
        "unindexed: its footer points outside the file" + scanning
    )
    reader = read(_with_footer(raw, start, offsets, crc ^ 1))
    assert reader.notes == ["the summary does not match its CRC; scanned the data section"]
    broken = bytearray(raw)
    broken[start + 1 : start + 9] = struct.pack("<Q", 2**40)  # a record longer than the file
    reader = read(_with_footer(bytes(broken), start, offsets, 0))
    assert reader.unindexed is not None
    assert reader.unindexed.startswith("unindexed: its summary is damaged (")
    # a sound file: read from its summary, with no note
    assert read(raw).unindexed is None and read(raw).indexed


def test_a_summary_without_offsets_ends_at_the_footer(tmp_path: Path) -> None:
    raw = write_sample(tmp_path / "x.mcap", 20).path.read_bytes()
    start = _footer(raw)[0]
    bad = tmp_path / "bad.mcap"
    # the spec allows summary_offset_start 0: the summary then runs up to the footer, and
    # the summary offset records in it are records of the summary like any other
    bad.write_bytes(_with_footer(raw, start, 0, 0))
    with McapReader(bad) as reader:
        assert reader.indexed and reader.unindexed is None
        assert reader.info().message_count == 20


def _extras_file(path: Path, attachments: int, metadata: int) -> Path:
    with open_writer(path) as writer:
        conn = writer.add_connection("/t", "std_msgs/String", STRING_MD5, "string data\n")
        writer.write(conn, 1, struct.pack("<I", 0))
        for i in range(attachments):
            writer.add_extra(fmt.Attachment(i, i, f"a{i}", "text/plain", b"x" * i, 0))
        for i in range(metadata):
            writer.add_extra(fmt.Metadata(f"m{i}", {"k": str(i)}))
    return path


@pytest.mark.parametrize(("attachments", "metadata"), [(2, 3), (0, 1), (1, 0)])
def test_attachments_and_metadata_are_counted_with_or_without_a_summary(
    tmp_path: Path, attachments: int, metadata: int
) -> None:
    whole = _extras_file(tmp_path / "x.mcap", attachments, metadata).read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(whole[:-1])
    for path in (tmp_path / "x.mcap", cut):
        with McapReader(path) as reader:
            info = reader.info()
            assert (info.attachment_count, info.metadata_count) == (attachments, metadata)
            names = [r.name for r in reader.extras()]
        assert names == [f"a{i}" for i in range(attachments)] + [f"m{i}" for i in range(metadata)]


def test_chunks_out_of_time_order_are_counted(tmp_path: Path) -> None:
    path = tmp_path / "x.mcap"
    write_late_chunk(path)
    with McapReader(path) as reader:
        late = reader.chunk_indexes[0].chunk_start_offset
        assert reader.chunk_checks() == ([], [f"chunk at {late}: 2 messages out of time order"])


def test_closing_unmaps_the_file(tmp_path: Path) -> None:
    path = write_sample(tmp_path / "x.mcap", 5).path
    reader = McapReader(path)
    info = reader.info()
    assert (info.path, info.version, info.connections) == (path, "0", tuple(reader.connections))
    assert Path("/proc/self/maps").read_text().count(str(path)) == 1
    reader.close()
    assert Path("/proc/self/maps").read_text().count(str(path)) == 0


def test_a_chunk_cut_short_is_read_as_far_as_it_goes(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.mcap", 200, compression="none", chunk_size=3000)
    raw = sample.path.read_bytes()
    with McapReader(sample.path) as reader:
        chunk = reader.chunk_indexes[1]
    cut = chunk.chunk_start_offset + chunk.chunk_length // 2
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(raw[:cut])
    with McapReader(bad) as reader:
        got = read_stream(bad)
        damage = list(reader.damage)
    assert got == sample.stream[: len(got)] and len(got) < len(sample.stream)
    assert damage[0] == f"chunk at {chunk.chunk_start_offset} is cut short; read what decompresses"
    assert damage[1].startswith(f"chunk at {chunk.chunk_start_offset} is cut short (")


SCHEMA = fmt.encode_schema(1, "std_msgs/String", "ros1msg", b"string data\n")
#: Where the data section of a handmade file starts: after the magic and the header.
DATA = len(fmt.MAGIC) + len(fmt.encode_header("ros1", ""))


def _channel(channel_id: int, topic: str, encoding: str = "ros1") -> bytes:
    return fmt.encode_channel(channel_id, 1, topic, encoding, {})


def _msg(channel_id: int, t: int, data: bytes = b"\0\0\0\0") -> bytes:
    return fmt.MESSAGE_PREFIX.pack(fmt.OP_MESSAGE, 22 + len(data), channel_id, 0, t, t) + data


def _chunk(records: bytes, start: int = 0, end: int = 0) -> bytes:
    return fmt.encode_chunk_head(start, end, len(records), "", len(records), 0) + records


def _read(reader: McapReader, **kwargs: object) -> list[tuple[str, int]]:
    return [(c.topic, t) for c, t, _ in reader.messages(**kwargs)]  # type: ignore[arg-type]


def test_damage_inside_chunks_is_said_where_it_is(tmp_path: Path) -> None:
    unknown = fmt.PREFIX.pack(0x80, 0)  # an opcode readers skip (MCAP spec)
    short = fmt.MESSAGE_PREFIX.pack(fmt.OP_MESSAGE, 10, 1, 0, 6, 6)[:19]  # 10 bytes of content
    bad_channel = fmt.PREFIX.pack(fmt.OP_CHANNEL, 3) + b"\0\0\0"
    chunks = [
        SCHEMA + _channel(1, "/t") + _msg(1, 1) + _msg(1, 2, b"") + unknown * 3,
        _msg(1, 3) + b"\x05\x01\x02",
        _msg(1, 4) + bad_channel + fmt.PREFIX.pack(0x80, 5),
        _msg(1, 5) + short + _msg(1, 6) + _msg(1, 7),
    ]
    records = b"".join(_chunk(c, 1, 7) for c in chunks)
    path = handmade_mcap(tmp_path / "x.mcap", "ros1", records + bad_channel + _msg(1, 8))
    at = [DATA]
    for c in chunks:
        at.append(at[-1] + len(_chunk(c)))
    inner = [a + len(_chunk(b"")) for a in at]  # where each chunk's records start
    tail = inner[1] + len(_msg(1, 3))
    cut = inner[2] + len(_msg(1, 4)) + len(bad_channel)
    too_short = inner[3] + len(_msg(1, 5))
    with McapReader(path) as reader:
        assert _read(reader) == [("/t", t) for t in range(1, 9)]
        assert reader.damage == [
            f"chunk at {at[1]} ends in a damaged record (record at {tail} is cut short)",
            f"chunk at {at[2]}: skipped a damaged channel record at {cut - len(bad_channel)}"
            " (record field of 2 bytes overruns its record)",
            f"chunk at {at[2]} ends in a damaged record (record at {cut} (5 bytes) is cut short"
            " or corrupt)",
            f"chunk at {at[3]}: {len(short)} bytes at {too_short} do not parse (message at"
            f" {too_short} is too short); read on at {too_short + len(short)}",
            f"skipped a damaged channel record at {at[4]} (record field of 2 bytes overruns its"
            " record)",
        ]


def test_loose_messages_between_chunks_are_read_in_time_order(tmp_path: Path) -> None:
    chunk = _chunk(SCHEMA + _channel(1, "/t") + _msg(1, 2), 2, 2)
    records = chunk + _msg(1, 9) + _msg(1, 1) + _chunk(_msg(1, 5), 5, 5) + _msg(1, 10)
    records += _msg(1, 3, b"") + fmt.MESSAGE_PREFIX.pack(fmt.OP_MESSAGE, 10, 1, 0, 6, 6)[:19]
    records += _msg(1, 4) + _msg(1, 11)
    path = handmade_mcap(tmp_path / "x.mcap", "ros1", records)
    short = DATA + len(chunk) + 2 * len(_msg(1, 0)) + len(_chunk(_msg(1, 5)))
    short += len(_msg(1, 10)) + len(_msg(1, 3, b""))
    with McapReader(path) as reader:
        assert _read(reader) == [("/t", t) for t in (1, 2, 3, 4, 5, 9, 10, 11)]
        assert _read(reader, start=9, end=10) == [("/t", 9), ("/t", 10)]
        assert reader.damage == [
            f"19 bytes at {short} do not parse (message at {short} is too short);"
            f" read on at {short + 19}"
        ]
    # unfinished: the messages after the last chunk run to the end of the file
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(path.read_bytes()[: DATA + len(records)])
    with McapReader(cut) as reader:
        assert _read(reader) == [("/t", t) for t in (1, 2, 3, 4, 5, 9, 10, 11)]
    # cut inside its last message: reading on after damage needs two whole records
    cut.write_bytes(path.read_bytes()[: DATA + len(records) - 3])
    with McapReader(cut) as reader:
        assert _read(reader) == [("/t", t) for t in (1, 2, 3, 5, 9, 10)]
        assert reader.damage == [
            f"data section ends in a damaged or cut-short record (message at {short} is too short)"
        ]


def test_a_chunk_that_does_not_decompress_is_named_by_the_scan(tmp_path: Path) -> None:
    junk = fmt.encode_chunk_head(1, 1, 10, "zstd", 8, 0) + b"\0" * 8
    records = SCHEMA + _channel(1, "/t") + junk + _chunk(_msg(1, 2), 2, 2)
    with McapReader(handmade_mcap(tmp_path / "x.mcap", "ros1", records)) as reader:
        assert _read(reader) == [("/t", 2)]
        said = reader.damage[0]
        # the scan meets it first, then the read
        assert reader.damage == [said, f"{said}; its messages are left out"]
    at = DATA + len(SCHEMA) + len(_channel(1, "/t"))
    assert said.startswith(f"chunk at {at} is unreadable (zstd chunk does not decompress: ")


def _summary_file(path: Path, records: bytes, count: int, start: int, end: int) -> Path:
    """An indexed MCAP file whose summary holds statistics alone, with no counts per channel
    (valid: an empty map says the statistic is not there), so channels are met while reading."""
    data = fmt.MAGIC + fmt.encode_header("ros1", "") + records + fmt.encode_data_end()
    stats = fmt.Statistics(count, 1, 2, 0, 0, 2, start, end, {})
    summary = fmt.encode_statistics(stats)
    path.write_bytes(data + summary + fmt.encode_footer(len(data), 0, summary))
    return path


def test_channels_met_inside_chunks_while_reading(tmp_path: Path) -> None:
    # the second channel's record is short: the last record of its chunk, under a message's size
    first = SCHEMA + _channel(1, "/t") + _msg(1, 1) + _channel(2, "/u", "")
    assert len(_channel(2, "/u", "")) < fmt.MESSAGE_PREFIX.size
    records = _chunk(first, 1, 1) + _chunk(_msg(2, 3) + _msg(1, 4), 3, 4)
    path = _summary_file(tmp_path / "x.mcap", records, 3, 1, 4)
    with McapReader(path) as reader:
        assert reader.indexed and reader.connections == []
        assert _read(reader) == [("/t", 1), ("/u", 3), ("/t", 4)]
        assert reader.damage == [] and reader.notes == []


def test_an_unreadable_chunk_is_left_out_and_named(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.mcap", 50, compression="zstd", chunk_size=2000)
    raw = sample.path.read_bytes()
    with McapReader(sample.path) as reader:
        index = reader.chunk_indexes[1]
        inside = [
            m for m in sample.stream if index.message_start_time <= m[2] <= index.message_end_time
        ]
    data = index.chunk_start_offset + 9 + 40 + len(index.compression)
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(raw[:data] + b"\0" * 8 + raw[data + 8 :])
    with McapReader(bad) as reader:
        assert read_stream(bad) == [m for m in sample.stream if m not in inside]
        list(reader.messages())
        [said] = reader.damage
    assert said.startswith(f"chunk at {index.chunk_start_offset} is unreadable (zstd chunk ")
    assert said.endswith("); its messages are left out")


def test_chunk_times_and_a_partial_read(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.mcap", 50, chunk_size=2000)
    raw = sample.path.read_bytes()
    with McapReader(sample.path) as reader:
        index = reader.chunk_indexes[1]
    rec, start, end = index.chunk_start_offset, index.message_start_time, index.message_end_time
    topic = next(m[0] for m in sample.stream if m[2] == end)
    first = min(m[2] for m in sample.stream if m[0] == topic and m[2] >= start)
    bad = tmp_path / "bad.mcap"
    mismatch = f"the summary's index of the chunk at {rec} does not match it"
    for new_end, notes in (
        (end + 1, [mismatch]),
        (end - 1, [mismatch, f"chunk at {rec}: its messages run from {first} to {end} ns,"
                             f" its header says {start} to {end - 1}"]),
    ):  # fmt: skip
        bad.write_bytes(raw[: rec + 17] + struct.pack("<Q", new_end) + raw[rec + 25 :])
        with McapReader(bad) as reader:
            list(reader.messages(topics=[topic]))
            assert reader.notes == notes
