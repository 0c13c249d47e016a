"""The rosbag v2.0 record codec: round trips, truncation, chunk compression."""

from __future__ import annotations

import os

import pytest
from hypothesis import given, strategies as st

from rostools.bag.formats import rosbag1_format as fmt

field_names = st.text(
    alphabet=st.characters(min_codepoint=33, max_codepoint=126, exclude_characters="="),
    min_size=1,
    max_size=12,
)
headers = st.dictionaries(field_names, st.binary(max_size=40), max_size=6)


@given(headers, st.binary(max_size=300))
def test_record_round_trip(fields: dict[str, bytes], data: bytes) -> None:
    raw = b"junk" + fmt.encode_record(fields, data)
    parsed, start, length = fmt.read_record(raw, 4, len(raw))
    assert parsed == fields
    assert raw[start : start + length] == data
    assert start + length == len(raw)


@given(headers, st.binary(max_size=100), st.data())
def test_cut_record_is_an_error(fields: dict[str, bytes], data: bytes, pick: st.DataObject) -> None:
    raw = fmt.encode_record(fields, data)
    cut = pick.draw(st.integers(0, len(raw) - 1))
    with pytest.raises(fmt.RecordError):
        fmt.read_record(raw, 0, cut)


def test_header_fields_are_sorted_as_the_cpp_writer_writes_them() -> None:
    header = fmt.encode_header({"op": b"\x02", "time": b"\0" * 8, "conn": b"\0" * 4})
    assert header.index(b"conn=") < header.index(b"op=") < header.index(b"time=")


@given(st.integers(0, (1 << 32) * 1_000_000_000 - 1))
def test_time_round_trip(t: int) -> None:
    assert fmt.unpack_time(fmt.pack_time(t)) == t


def test_field_readers_reject_wrong_widths() -> None:
    with pytest.raises(fmt.RecordError):
        fmt.u32_field({"conn": b"\0\0"}, "conn")
    with pytest.raises(fmt.RecordError):
        fmt.u64_field({}, "index_pos")
    with pytest.raises(fmt.RecordError):
        fmt.op_of({"op": b""})


@pytest.mark.parametrize("kind", fmt.COMPRESSIONS)
def test_compression_round_trip(kind: str) -> None:
    data = os.urandom(5000) + bytes(300_000) + b"tail"
    packed = fmt.compress(kind, data)
    assert fmt.decompress(kind, packed, len(data)) == data


def test_lz4_frames_use_roslz4_settings() -> None:
    frame = fmt.lz4_compress(os.urandom(800_000))
    # Magic, then FLG 0x64 (version 1, independent blocks, content checksum, no size) and
    # BD 0x60 (1 MB blocks): exactly what roslz4 writes. (liblz4 picks smaller blocks for a
    # small chunk; roslz4 reads those as long as they are independent.)
    assert frame[:4] == b"\x04\x22\x4d\x18"
    assert frame[4:6] == b"\x64\x60"


def test_decompress_checks_the_declared_size() -> None:
    packed = fmt.compress("bz2", b"x" * 100)
    with pytest.raises(fmt.RecordError, match="header says"):
        fmt.decompress("bz2", packed, 99)


def test_a_cut_lz4_chunk_salvages_its_complete_blocks() -> None:
    import lz4.frame

    data = os.urandom(300_000)
    frame = lz4.frame.compress(
        data, block_size=lz4.frame.BLOCKSIZE_MAX64KB, block_linked=False, content_checksum=True
    )
    salvaged = fmt.decompress_prefix("lz4", frame[: len(frame) // 2], len(data))
    assert 0 < len(salvaged) < len(data)
    assert data.startswith(salvaged)


def test_corrupt_chunk_data_is_a_record_error() -> None:
    with pytest.raises(fmt.RecordError):
        fmt.decompress("bz2", b"BZh9 not really", 10)


def test_unknown_compression_is_unsupported() -> None:
    from rostools.bag.formats.model import UnsupportedBagError

    with pytest.raises(UnsupportedBagError):
        fmt.compress("zstd", b"")
