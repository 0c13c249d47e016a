"""Our MCAP files as the ``mcap`` library (an independent reader) sees them, and MCAP edges."""

from __future__ import annotations

import zlib
from pathlib import Path

import pytest

from rostools.bag.formats import mcap_format as fmt
from rostools.bag.formats.mcap_reader import McapReader
from tests.support.bagdata import SAMPLE_CONNECTIONS, write_sample


@pytest.mark.parametrize("compression", ["zstd", "lz4", "none"])
def test_the_mcap_library_reads_our_files(tmp_path: Path, compression: str) -> None:
    from mcap.reader import make_reader

    sample = write_sample(tmp_path / "x.mcap", 300, compression=compression, chunk_size=3000)
    with sample.path.open("rb") as f:
        reader = make_reader(f)
        header = reader.get_header()
        summary = reader.get_summary()
        got = [
            (channel.topic, channel.metadata["callerid"], message.log_time, message.data)
            for _, channel, message in reader.iter_messages(log_time_order=True)
        ]
    assert got == sample.stream
    assert header.profile == "ros1"
    assert summary is not None
    assert summary.statistics.message_count == 300
    assert len(summary.chunk_indexes) == summary.statistics.chunk_count > 1
    assert {s.encoding for s in summary.schemas.values()} == {"ros1msg"}
    assert {c.message_encoding for c in summary.channels.values()} == {"ros1"}
    first = summary.channels[0]
    assert first.metadata == {
        "callerid": "/talker",
        "latching": "true",
        "md5sum": SAMPLE_CONNECTIONS[0][2],
    }
    assert summary.channels[1].metadata["latching"] == "false"
    assert summary.schemas[first.schema_id].data == b"string data\n"
    # One schema per distinct definition: the two /chatter publishers share theirs.
    assert len(summary.schemas) == 3


def test_summary_and_data_crcs(tmp_path: Path) -> None:
    from mcap.stream_reader import StreamReader

    sample = write_sample(tmp_path / "x.mcap", 100)
    raw = sample.path.read_bytes()
    footer = fmt.parse_footer(raw)
    assert footer is not None
    summary_and_footer = raw[footer.summary_start : len(raw) - len(fmt.MAGIC) - 4]
    assert zlib.crc32(summary_and_footer) == footer.summary_crc
    with sample.path.open("rb") as f:
        assert sum(1 for _ in StreamReader(f, validate_crcs=True).records) > 100


def test_info_reads_only_the_summary(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.mcap", 100)
    with McapReader(sample.path) as reader:
        assert reader.indexed
        info = reader.info()
        assert reader._scan_result is None  # no walk over the data section
    assert info.message_count == 100
    assert info.profile == "ros1"
    assert info.library.startswith("rostools")


def test_unfinished_mcap_reads_every_closed_chunk(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.mcap", 300, chunk_size=2000, close=False)
    with McapReader(sample.path) as reader:
        assert not reader.indexed
        assert reader.notes
        got = [(c.topic, c.callerid, t, bytes(d)) for c, t, d in reader.messages()]
        assert reader.info().message_count == 300
    assert got == sample.stream


@pytest.mark.parametrize("compression", ["none", "lz4", "zstd"])
def test_cut_mcap_salvages_a_prefix(tmp_path: Path, compression: str) -> None:
    sample = write_sample(tmp_path / "x.mcap", 400, compression=compression, chunk_size=8000)
    raw = sample.path.read_bytes()
    for cut in range(60, len(raw), 997):  # past the header record
        part = tmp_path / f"cut{cut}.mcap"
        part.write_bytes(raw[:cut])
        with McapReader(part) as reader:
            got = [(c.topic, c.callerid, t, bytes(d)) for c, t, d in reader.messages()]
        assert got == sample.stream[: len(got)]


def test_non_ros1_profiles_are_described(tmp_path: Path) -> None:
    path = tmp_path / "json.mcap"
    out = bytearray(fmt.MAGIC)
    out += fmt.encode_header("", "handmade")
    out += fmt.encode_schema(1, "Thing", "jsonschema", b"{}")
    out += fmt.encode_channel(3, 1, "/json", "json", {"owner": "me"})
    out += fmt.MESSAGE_PREFIX.pack(fmt.OP_MESSAGE, 22 + 2, 3, 0, 7, 7) + b"{}"
    out += fmt.encode_data_end()
    out += fmt.encode_footer(0, 0, b"")
    path.write_bytes(bytes(out))
    with McapReader(path) as reader:
        info = reader.info()
        ((conn, t, data),) = list(reader.messages())
    assert not info.indexed
    assert (info.profile, info.message_count, info.start_ns) == ("", 1, 7)
    assert (conn.id, conn.topic, conn.type, conn.md5sum, conn.extra) == (
        3,
        "/json",
        "Thing",
        "",
        {"owner": "me"},
    )
    assert (t, bytes(data)) == (7, b"{}")


def test_missing_md5_is_computed_from_a_ros1_definition(tmp_path: Path) -> None:
    path = tmp_path / "nomd5.mcap"
    out = bytearray(fmt.MAGIC)
    out += fmt.encode_header("ros1", "")
    out += fmt.encode_schema(1, "std_msgs/String", "ros1msg", b"string data\n")
    out += fmt.encode_channel(0, 1, "/s", "ros1", {})
    out += fmt.encode_data_end()
    out += fmt.encode_footer(0, 0, b"")
    path.write_bytes(bytes(out))
    with McapReader(path) as reader:
        (conn,) = reader.connections
    assert conn.md5sum == "992ce8a1687cec8c8bd883ec73ca41d1"
    assert conn.absent == {"latching"}


def test_messages_of_undefined_channels_are_reported(tmp_path: Path) -> None:
    path = tmp_path / "orphan.mcap"
    out = bytearray(fmt.MAGIC)
    out += fmt.encode_header("ros1", "")
    out += fmt.MESSAGE_PREFIX.pack(fmt.OP_MESSAGE, 22 + 1, 9, 0, 5, 5) + b"x"
    out += fmt.encode_data_end()
    out += fmt.encode_footer(0, 0, b"")
    path.write_bytes(bytes(out))
    with McapReader(path) as reader:
        assert list(reader.messages()) == []
        assert any("channel 9" in d for d in reader.damage)
