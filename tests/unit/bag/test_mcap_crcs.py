"""CRCs in the MCAP files we write (chunks, data section, summary), and who catches a flip.

The ``mcap`` package is the independent reader: its CRC validation must accept every file we
write, in every compression, and refuse one with a flipped bit in a chunk.
"""

from __future__ import annotations

import struct
import zlib
from pathlib import Path

import pytest

from rostools.bag.formats import mcap_format as fmt
from rostools.bag.formats.access import open_writer
from rostools.bag.formats.mcap_reader import McapReader
from rostools.bag.tools.findings import doctor
from rostools.bag.tools.ops import convert
from rostools.bag.tools.options import CopyOptions
from tests.support.bagdata import STRING_MD5, read_stream, write_sample

COMPRESSIONS = ["none", "lz4", "zstd"]
#: Big enough to be queued by reference (sink.BIG_PAYLOAD), so the CRC sees every piece kind.
BIG = 40_000


def big(i: int) -> bytes:
    """A message too big to be copied into the writer's buffer, a function of ``i``."""
    body = bytes((i * 7 + k) & 0xFF for k in range(251)) * (BIG // 251)
    return len(body).to_bytes(4, "little") + body


def write_mixed(path: Path, compression: str) -> list[tuple[int, bytes]]:
    """Small and big messages over several chunks, an attachment and a metadata record."""
    out = []
    with open_writer(path, compression=compression, chunk_size=60_000) as writer:
        small = writer.add_connection("/s", "std_msgs/String", STRING_MD5, "string data\n")
        large = writer.add_connection("/b", "std_msgs/String", STRING_MD5, "string data\n")
        writer.add_extra(fmt.Attachment(5, 6, "notes.txt", "text/plain", b"hello", 0))  # type: ignore[attr-defined]
        writer.add_extra(fmt.Metadata("robot", {"name": "r2"}))  # type: ignore[attr-defined]
        for i in range(60):
            data = big(i) if i % 5 == 0 else b"\x05\x00\x00\x00hello"
            writer.write(large if i % 5 == 0 else small, i * 1000, data)
            out.append((i * 1000, data))
    return out


def top_records(raw: bytes) -> list[tuple[int, int, int, int]]:
    """(record, opcode, content start, content end) of the data section's records."""
    found = []
    for rec, op, start, stop in fmt.records(raw, len(fmt.MAGIC), len(raw)):
        found.append((rec, op, start, stop))
        if op == fmt.OP_DATA_END:
            break
    return found


def chunk_records_span(raw: bytes, start: int) -> tuple[int, int]:
    """(start, end) of a chunk record's (stored) records, given its content start."""
    (clen,) = struct.unpack_from("<I", raw, start + 28)
    (dlen,) = struct.unpack_from("<Q", raw, start + 32 + clen)
    return start + 40 + clen, start + 40 + clen + dlen


@pytest.mark.parametrize("compression", COMPRESSIONS)
def test_every_crc_is_written(tmp_path: Path, compression: str) -> None:
    path = tmp_path / "x.mcap"
    write_mixed(path, compression)
    assert check_crcs(path) > 2


def check_crcs(path: Path) -> int:
    """Every chunk, the data section and the summary carry their CRC, and it is right."""
    raw = path.read_bytes()
    chunks = 0
    for rec, op, start, stop in top_records(raw):
        if op == fmt.OP_CHUNK:
            chunk = fmt.parse(op, raw, start, stop)
            assert isinstance(chunk, fmt.McapChunk)
            records = fmt.decompress(chunk.compression, chunk.records, chunk.uncompressed_size)
            assert chunk.uncompressed_crc == zlib.crc32(records) != 0
            chunks += 1
        elif op == fmt.OP_DATA_END:
            (crc,) = struct.unpack_from("<I", raw, start)
            assert crc == zlib.crc32(raw[:rec]) != 0
    footer = fmt.parse_footer(raw)
    assert footer is not None
    summary_and_footer = raw[footer.summary_start : len(raw) - len(fmt.MAGIC) - 4]
    assert footer.summary_crc == zlib.crc32(summary_and_footer) != 0
    return chunks


def _mcap_package_reads(path: Path) -> list[tuple[int, bytes]]:
    """Every message through the ``mcap`` package with CRC validation on, both readers."""
    from mcap.reader import make_reader
    from mcap.records import Message
    from mcap.stream_reader import StreamReader

    with path.open("rb") as f:  # seeking: chunk CRCs
        reader = make_reader(f, validate_crcs=True)
        got = [(m.log_time, m.data) for _, _, m in reader.iter_messages()]
    with path.open("rb") as f:  # streaming: chunk CRCs and the data section's
        records = list(StreamReader(f, validate_crcs=True).records)
    assert sum(isinstance(r, Message) for r in records) == len(got)
    return got


@pytest.mark.parametrize("compression", COMPRESSIONS)
def test_the_mcap_package_validates_our_crcs(tmp_path: Path, compression: str) -> None:
    path = tmp_path / "x.mcap"
    sent = write_mixed(path, compression)
    assert _mcap_package_reads(path) == sent


@pytest.mark.parametrize("compression", COMPRESSIONS)
def test_converted_files_carry_crcs(tmp_path: Path, compression: str) -> None:
    """.bag -> MCAP takes the chunk-for-chunk fast path (``fastcopy``); MCAP -> MCAP does not."""
    sample = write_sample(tmp_path / "x.bag", 3000, chunk_size=9000)
    convert(sample.path, tmp_path / "fast.mcap", CopyOptions(compression=compression))
    again = tmp_path / "again.mcap"
    convert(tmp_path / "fast.mcap", again, CopyOptions(compression=compression, chunk_size=20_000))
    for name in ("fast.mcap", "again.mcap"):
        assert check_crcs(tmp_path / name) > 2
        got = _mcap_package_reads(tmp_path / name)
        assert got == [(t, d) for _, _, t, d in sample.stream]
        assert read_stream(tmp_path / name) == sample.stream
        assert doctor(tmp_path / name).clean


def flip(path: Path, at: int) -> Path:
    """A copy of ``path`` with one bit of the byte at ``at`` flipped."""
    raw = bytearray(path.read_bytes())
    raw[at] ^= 0x10
    out = path.with_name(f"flipped-{at}-{path.name}")
    out.write_bytes(bytes(raw))
    return out


@pytest.mark.parametrize("compression", COMPRESSIONS)
def test_a_flipped_bit_in_a_chunk_is_caught(tmp_path: Path, compression: str) -> None:
    from mcap.reader import make_reader
    from mcap.stream_reader import CRCValidationError

    path = tmp_path / "x.mcap"
    write_mixed(path, compression)
    raw = path.read_bytes()
    rec, _, start, _ = next(r for r in top_records(raw) if r[1] == fmt.OP_CHUNK)
    lo, hi = chunk_records_span(raw, start)
    # Uncompressed: a byte of the first message's data, so every record still parses.
    bad = flip(path, lo + 31 + 2 if compression == "none" else (lo + hi) // 2)
    with bad.open("rb") as f, pytest.raises(Exception) as caught:
        list(make_reader(f, validate_crcs=True).iter_messages())
    if compression == "none":
        assert caught.type is CRCValidationError
    report = doctor(bad)
    assert not report.clean
    if compression == "none":
        inner = sum(op == fmt.OP_MESSAGE for _, op, _, _ in fmt.records(raw, lo, hi))
        crc = f"chunk at {rec}: its CRC does not match its records"
        # None of the chunk's messages can be shown intact: every one is left out, and said.
        assert [f for f in report.findings if "CRC" in f] == [
            f"{crc}; its {inner} messages are left out"
        ]
        assert f"the index counts 60 messages but {60 - inner} were read" in report.findings
        assert report.messages == 60 - inner
        with McapReader(bad) as reader:
            assert len(list(reader.messages())) == 60 - inner
            assert reader.damage == [f"{crc}; its {inner} messages are left out"]
        with McapReader(bad) as reader:
            reader.check_crcs = False  # --no-crc-check: read as it is
            assert len(list(reader.messages())) == 60 and not reader.damage


def test_doctor_names_a_data_section_crc_mismatch(tmp_path: Path) -> None:
    path = tmp_path / "x.mcap"
    write_mixed(path, "zstd")
    raw = path.read_bytes()
    # A byte of the header's library name: only the data section's CRC covers it.
    bad = flip(path, raw.index(b"rostools ") + 2)
    assert "the data section's CRC does not match its bytes" in doctor(bad).findings
    assert doctor(path).clean


def test_a_summary_that_fails_its_crc_is_not_trusted(tmp_path: Path) -> None:
    """A flipped bit in the statistics would make ``info`` count wrong, silently."""
    path = tmp_path / "x.mcap"
    write_mixed(path, "lz4")
    raw = path.read_bytes()
    footer = fmt.parse_footer(raw)
    assert footer is not None
    stats = next(
        start
        for _, op, start, _ in fmt.records(raw, footer.summary_start, footer.summary_offset_start)
        if op == fmt.OP_STATISTICS
    )
    bad = flip(path, stats)  # the low byte of the message count
    with McapReader(bad) as reader:
        assert reader.info().message_count == 60
        assert any("summary" in n and "CRC" in n for n in reader.notes)
        assert len(list(reader.messages())) == 60
    report = doctor(bad)
    assert any("summary" in f and "CRC" in f for f in report.findings)
    assert report.recover_helps


def test_recover_and_merge_write_crcs(tmp_path: Path) -> None:
    from rostools.bag.tools.merge import merge
    from rostools.bag.tools.recover import recover

    sample = write_sample(tmp_path / "open.mcap", 3000, chunk_size=9000, close=False)
    recover(sample.path, tmp_path / "recovered.mcap", chunk_size=20_000)
    other = write_sample(tmp_path / "x.bag", 500)
    merge(
        [tmp_path / "recovered.mcap", other.path],
        tmp_path / "merged.mcap",
        CopyOptions(chunk_size=20_000),
    )
    for name, count in (("recovered.mcap", 3000), ("merged.mcap", 3500)):
        assert check_crcs(tmp_path / name) > 2
        assert len(_mcap_package_reads(tmp_path / name)) == count


def test_a_file_without_summary_counts_no_chunk_that_fails_its_crc(tmp_path: Path) -> None:
    """An unfinished file is counted by a scan of its chunks: the scan checks their CRCs."""
    sample = write_sample(
        tmp_path / "x.mcap", 400, compression="none", chunk_size=3000, close=False
    )
    raw = sample.path.read_bytes()
    rec, _, start, _ = next(r for r in top_records(raw) if r[1] == fmt.OP_CHUNK)
    lo, hi = chunk_records_span(raw, start)
    inner = [at for at, op, _, _ in fmt.records(raw, lo, hi) if op == fmt.OP_MESSAGE]
    bad = flip(sample.path, inner[0] + 31 + 4)  # a byte of the first message's data
    said = (
        f"chunk at {rec}: its CRC does not match its records; its {len(inner)} messages are"
        " left out"
    )
    with McapReader(bad) as reader:
        assert reader.unindexed is not None
        assert reader.info().message_count == 400 - len(inner)
        assert reader.damage == [said]
        assert len(list(reader.messages())) == 400 - len(inner)
        assert reader.damage == [said]  # said once, by the scan and the read alike
