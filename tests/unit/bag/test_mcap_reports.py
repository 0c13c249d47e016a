"""What the MCAP reader says about a file: its errors, notes and damage, word for word.

Positions come from the MCAP layout (https://mcap.dev/spec): magic, header, data section,
data end, summary, summary offsets, footer (its last 28 bytes before the closing magic).
"""

from __future__ import annotations

import struct
from pathlib import Path

import pytest

from rostools.bag import mcap_format as fmt
from rostools.bag.access import open_writer
from rostools.bag.mcap_reader import McapReader
from rostools.bag.model import BagFormatError
from tests.support.bagdata import STRING_MD5, read_stream, write_late_chunk, write_sample

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
