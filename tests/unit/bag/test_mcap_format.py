"""The MCAP record codec: every record we write parses back; truncation is an error."""

from __future__ import annotations

import struct
import zlib

import pytest
from hypothesis import given, strategies as st

from rostools.bag.formats import mcap_format as fmt

text = st.text(max_size=20)
u16 = st.integers(0, 0xFFFF)
u64 = st.integers(0, (1 << 64) - 1)
str_maps = st.dictionaries(text, text, max_size=4)
id_maps = st.dictionaries(u16, u64, max_size=4)


def parse_one(raw: bytes) -> fmt.Record | None:
    ((_, op, start, stop),) = list(fmt.records(raw, 0, len(raw)))
    return fmt.parse(op, raw, start, stop)


@given(u16, text, text, st.binary(max_size=50))
def test_schema_round_trip(sid: int, name: str, encoding: str, data: bytes) -> None:
    assert parse_one(fmt.encode_schema(sid, name, encoding, data)) == fmt.Schema(
        sid, name, encoding, data
    )


@given(u16, u16, text, text, str_maps)
def test_channel_round_trip(cid: int, sid: int, topic: str, enc: str, meta: dict[str, str]) -> None:
    record = parse_one(fmt.encode_channel(cid, sid, topic, enc, meta))
    assert record == fmt.Channel(cid, sid, topic, enc, meta)


@given(u64, u64, u16, u64, u64, u64, id_maps, text, u64, u64)
def test_chunk_index_round_trip(
    a: int,
    b: int,
    c: int,
    d: int,
    e: int,
    f: int,
    offsets: dict[int, int],
    comp: str,
    g: int,
    h: int,
) -> None:
    index = fmt.ChunkIndex(a, b, d, e, offsets, f, comp, g, h)
    assert parse_one(fmt.encode_chunk_index(index)) == index


@given(u64, u16, st.integers(0, 2**32 - 1), id_maps)
def test_statistics_round_trip(n: int, schemas: int, channels: int, counts: dict[int, int]) -> None:
    stats = fmt.Statistics(n, schemas, channels, 1, 2, 3, 4, 5, counts)
    assert parse_one(fmt.encode_statistics(stats)) == stats


@given(st.lists(st.tuples(u64, u64), max_size=5))
def test_message_index_round_trip(entries: list[tuple[int, int]]) -> None:
    packed = b"".join(struct.pack("<QQ", t, o) for t, o in entries)
    assert parse_one(fmt.encode_message_index(7, packed)) == fmt.MessageIndex(7, entries)


def test_message_prefix_is_a_message_record() -> None:
    raw = fmt.MESSAGE_PREFIX.pack(fmt.OP_MESSAGE, 22 + 3, 9, 4, 100, 200) + b"abc"
    assert parse_one(raw) == fmt.MessageRecord(9, 4, 100, 200, b"abc")


def test_padding_after_known_fields_is_ignored() -> None:
    raw = fmt.encode_data_end(5)
    padded = fmt.PREFIX.pack(fmt.OP_DATA_END, 4 + 3) + raw[9:] + b"pad"
    assert parse_one(padded) == fmt.DataEnd(5)


def test_unknown_opcodes_parse_to_none() -> None:
    assert parse_one(fmt.PREFIX.pack(0x80, 2) + b"xy") is None


def test_footer_crc_covers_the_summary_and_footer_fields() -> None:
    summary = fmt.encode_schema(1, "a/B", "ros1msg", b"int32 x\n")
    tail = fmt.encode_footer(100, 150, summary)
    footer = fmt.parse_footer(tail)
    assert footer is not None
    assert footer.summary_start == 100
    assert footer.summary_offset_start == 150
    assert footer.summary_crc == zlib.crc32(summary + tail[: fmt.FOOTER_SIZE - 4])
    assert tail.endswith(fmt.MAGIC)


def test_no_footer_without_the_closing_magic() -> None:
    assert fmt.parse_footer(b"\0" * 45) is None


@given(st.data())
def test_cut_records_raise(pick: st.DataObject) -> None:
    raw = fmt.encode_channel(1, 1, "/t", "ros1", {"a": "b"})
    cut = pick.draw(st.integers(1, len(raw) - 1))
    with pytest.raises(fmt.McapFormatError):
        list(fmt.records(raw, 0, cut))


def test_lying_inner_lengths_raise() -> None:
    content = struct.pack("<H", 1) + struct.pack("<I", 1000) + b"short"
    with pytest.raises(fmt.McapFormatError):
        fmt.parse(fmt.OP_SCHEMA, content, 0, len(content))


@pytest.mark.parametrize("compression", ["", "zstd", "lz4"])
def test_chunk_decompression(compression: str) -> None:
    import lz4.frame
    import zstandard

    data = b"records " * 5000
    packed = {
        "": data,
        "zstd": zstandard.ZstdCompressor().compress(data),
        "lz4": lz4.frame.compress(data),
    }[compression]
    assert fmt.decompress(compression, packed, len(data)) == data
    with pytest.raises(fmt.McapFormatError):
        fmt.decompress(compression, packed, len(data) - 1)


def test_unknown_chunk_compression_is_unsupported() -> None:
    from rostools.bag.formats.model import UnsupportedBagError

    with pytest.raises(UnsupportedBagError):
        fmt.decompress("brotli", b"", 0)


@given(st.binary(max_size=3000), st.binary(max_size=3000), st.integers(0, 2**32 - 1))
def test_crc32_combine_is_the_crc_of_the_concatenation(a: bytes, b: bytes, seed: int) -> None:
    assert fmt.crc32_combine(zlib.crc32(a, seed), zlib.crc32(b), len(b)) == zlib.crc32(
        b, zlib.crc32(a, seed)
    )


def test_crc32_combine_over_a_long_stretch() -> None:
    """A chunk's length in bits needs many of the squares (x^(2^k)), not only the first few."""
    a, b = b"head", bytes(range(256)) * 40_000
    assert fmt.crc32_combine(zlib.crc32(a), zlib.crc32(b), len(b)) == zlib.crc32(a + b)
