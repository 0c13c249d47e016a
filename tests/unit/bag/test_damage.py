"""Damaged files: whatever the damage, readers raise our errors, never a raw exception."""

from __future__ import annotations

import contextlib
import random
import re
import struct
from pathlib import Path

import pytest

from rostools.bag.formats import mcap_format, rosbag1_format as fmt
from rostools.bag.formats.access import bag_info, open_bag, open_writer
from rostools.bag.formats.mcap_reader import McapReader
from rostools.bag.formats.rosbag1_reader import Bag1Reader
from rostools.bag.tools.findings import doctor
from rostools.bag.tools.ops import convert
from rostools.bag.tools.recover import recover
from rostools.errors import DataLossError, RostoolsError
from tests.support.bagdata import (
    INT32_MD5,
    Record,
    Sample,
    bag_records,
    chunk_spans,
    headers,
    read_stream,
    swap_spans,
    write_sample,
)

CASES = [
    ("x.bag", "none"),
    ("x.bag", "bz2"),
    ("x.bag", "lz4"),
    ("x.mcap", "zstd"),
    ("x.mcap", "lz4"),
    ("x.mcap", "none"),
]


def read_everything(path: Path) -> None:
    with open_bag(path) as reader:
        reader.info()
        for _ in reader.messages():
            pass
        for _ in reader.times():
            pass


@pytest.mark.parametrize(("name", "compression"), CASES)
def test_random_damage_gives_our_errors(tmp_path: Path, name: str, compression: str) -> None:
    sample = write_sample(tmp_path / name, 300, compression=compression, chunk_size=3000)
    raw = sample.path.read_bytes()
    rng = random.Random(f"{name}{compression}")
    bad = tmp_path / ("bad" + Path(name).suffix)
    for _ in range(60):
        damaged = bytearray(raw)
        for _ in range(rng.randint(1, 4)):
            at = rng.randrange(len(raw))
            damaged[at : at + rng.randint(1, 16)] = rng.randbytes(rng.randint(1, 16))
        if rng.random() < 0.3:
            damaged = damaged[: rng.randrange(len(damaged))]
        bad.write_bytes(bytes(damaged))
        for action in (
            read_everything,
            lambda p: recover(p, tmp_path / "out" / p.name, overwrite=True),
        ):
            (tmp_path / "out").mkdir(exist_ok=True)
            try:
                action(bad)
            except RostoolsError as err:
                assert "\n" not in str(err)


# -- issue 24.3: damage never comes out silently wrong ------------------------------------

BAG_CASES = ["none", "bz2", "lz4"]


def _sample(tmp_path: Path, compression: str, count: int = 400) -> tuple[Sample, bytes]:
    sample = write_sample(tmp_path / "x.bag", count, compression=compression, chunk_size=3000)
    return sample, sample.path.read_bytes()


def _messages_and_reader(path: Path) -> tuple[list[tuple[str, str, int, bytes]], Bag1Reader]:
    reader = open_bag(path)
    assert isinstance(reader, Bag1Reader)
    with reader:
        got = [(c.topic, c.callerid, t, bytes(d)) for c, t, d in reader.messages()]
    return got, reader


def _index(raw: bytes, nth: int = 0) -> Record:
    return [r for r in bag_records(raw) if r[1] == fmt.OP_INDEX_DATA][nth]


@pytest.mark.parametrize("compression", BAG_CASES)
def test_message_times_come_from_the_records(tmp_path: Path, compression: str) -> None:
    sample, raw = _sample(tmp_path, compression)
    damaged = bytearray(raw)
    index = _index(raw, 1)
    damaged[index[3] + 12 * 2 + 3] ^= 0x04  # the third entry's seconds: + 2**26 s
    bad = tmp_path / "bad.bag"
    bad.write_bytes(bytes(damaged))
    got, reader = _messages_and_reader(bad)
    assert got == sample.stream
    assert not reader.damage
    assert [n for n in reader.notes if "index" in n and "records" in n], reader.notes
    report = recover(bad, tmp_path / "out.bag")
    assert report.complete and read_stream(tmp_path / "out.bag") == sample.stream
    assert bag_info(tmp_path / "out.bag").end_ns == sample.stream[-1][2]


@pytest.mark.parametrize("compression", BAG_CASES)
def test_an_index_entry_pointing_at_another_record(tmp_path: Path, compression: str) -> None:
    sample, raw = _sample(tmp_path, compression)
    damaged = bytearray(raw)
    index = _index(raw)
    # The second entry points where the first does: one message twice, another never.
    damaged[index[3] + 20 : index[3] + 24] = raw[index[3] + 8 : index[3] + 12]
    damaged[index[3] + 12 : index[3] + 20] = raw[index[3] : index[3] + 8]
    bad = tmp_path / "bad.bag"
    bad.write_bytes(bytes(damaged))
    got, reader = _messages_and_reader(bad)
    assert got == sample.stream
    assert any("index" in n for n in reader.notes), reader.notes


@pytest.mark.parametrize("compression", BAG_CASES)
def test_index_counts_that_disagree_with_the_records(tmp_path: Path, compression: str) -> None:
    sample, raw = _sample(tmp_path, compression)
    damaged = bytearray(raw)
    index = _index(raw)
    count = fmt.u32_field(index[2], "count")
    # The index claims one message fewer than the chunk holds.
    header = raw[index[0] : index[3]]
    where = header.index(b"count=") + 6
    damaged[index[0] + where : index[0] + where + 4] = fmt.U32.pack(count - 1)
    bad = tmp_path / "bad.bag"
    bad.write_bytes(bytes(damaged))
    got, reader = _messages_and_reader(bad)
    assert got == sample.stream
    assert any("index" in n for n in reader.notes), reader.notes


@pytest.mark.parametrize("compression", BAG_CASES)
def test_a_damaged_chunk_header_mid_file_hides_nothing_else(
    tmp_path: Path, compression: str
) -> None:
    sample, raw = _sample(tmp_path, compression)
    chunks = [r for r in bag_records(raw) if r[1] == fmt.OP_CHUNK]
    assert len(chunks) >= 5
    victim = chunks[2]
    bad = tmp_path / "bad.bag"
    bad.write_bytes(raw[: victim[0]] + bytes(victim[3] - victim[0]) + raw[victim[3] :])
    got, reader = _messages_and_reader(bad)
    assert any(str(victim[0]) in d for d in reader.damage), reader.damage
    if compression == "none":
        assert got == sample.stream  # only the chunk's header is lost: its records read on
    else:
        with open_bag(sample.path) as whole:
            lost = sum(1 for _ in whole.messages()) - len(got)
        assert 0 < lost < 200
        assert all(m in sample.stream for m in got)
        missing = [m for m in sample.stream if m not in got]
        times = [m[2] for m in missing]
        # What is missing is one run of messages: the damaged chunk's.
        assert missing == [m for m in sample.stream if min(times) <= m[2] <= max(times)]
    with pytest.raises(DataLossError) if reader.damage else contextlib.nullcontext():
        convert(bad, tmp_path / "out.mcap").raise_if_lost()
    assert read_stream(tmp_path / "out.mcap") == got


def test_a_damaged_message_record_mid_chunk_hides_nothing_else(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.bag", 200)  # one uncompressed chunk
    raw = sample.path.read_bytes()
    chunk = next(r for r in bag_records(raw) if r[1] == fmt.OP_CHUNK)
    inner = [r for r in bag_records(raw, chunk[3], chunk[3] + chunk[4]) if r[1] == fmt.OP_MSG_DATA]
    victim = inner[100]
    bad = tmp_path / "bad.bag"
    bad.write_bytes(raw[: victim[0]] + bytes(victim[3] - victim[0]) + raw[victim[3] :])
    got, reader = _messages_and_reader(bad)
    assert got == sample.stream[:100] + sample.stream[101:]
    assert reader.damage
    # Without its index (cut where the index starts), the walk gives the same messages.
    bad.write_bytes(bad.read_bytes()[: chunk_spans(raw)[-1][1]])
    got, reader = _messages_and_reader(bad)
    assert got == sample.stream[:100] + sample.stream[101:] and reader.damage


@pytest.mark.parametrize("compression", BAG_CASES)
def test_chunks_before_their_connection_records(tmp_path: Path, compression: str) -> None:
    sample, raw = _sample(tmp_path, compression)
    spans = chunk_spans(raw)
    bad = tmp_path / "bad.bag"
    bad.write_bytes(swap_spans(raw, spans[0], spans[3]))
    got, reader = _messages_and_reader(bad)
    assert sorted(got, key=lambda m: m[2]) == sample.stream
    assert not reader.damage and reader.notes
    report = recover(bad, tmp_path / "out.bag")
    assert report.complete and read_stream(tmp_path / "out.bag") == sample.stream


@pytest.mark.parametrize(("compression", "chunk_size"), [("bz2", 3000), ("lz4", 3000), ("bz2", 1)])
def test_an_unreadable_chunk_is_left_out_and_named(
    tmp_path: Path, compression: str, chunk_size: int
) -> None:
    sample = write_sample(tmp_path / "x.bag", 400, compression=compression, chunk_size=chunk_size)
    raw = sample.path.read_bytes()
    victim = [r for r in bag_records(raw) if r[1] == fmt.OP_CHUNK][1]
    damaged = bytearray(raw)
    middle = victim[3] + victim[4] // 2
    damaged[middle : middle + 8] = bytes(8)
    bad = tmp_path / "bad.bag"
    bad.write_bytes(bytes(damaged))
    got, reader = _messages_and_reader(bad)  # no exception: the other chunks still read
    assert got and all(m in sample.stream for m in got) and len(got) < len(sample.stream)
    lost = len(sample.stream) - len(got)
    lost_text = "1 message is" if lost == 1 else f"{lost} messages are"
    [said] = reader.damage
    assert re.fullmatch(rf"chunk at {victim[0]} is unreadable \(.+\); its {lost_text} lost", said)
    report = convert(bad, tmp_path / "out.bag")
    assert report.messages_written == len(got) and report.lost


def _mcap_chunks(path: Path) -> list[int]:
    with McapReader(path) as reader:
        return [i.chunk_start_offset for i in reader.chunk_indexes]


@pytest.mark.parametrize("compression", ["zstd", "lz4", "none"])
def test_mcap_a_damaged_chunk_header_mid_file_hides_nothing_else(
    tmp_path: Path, compression: str
) -> None:
    sample = write_sample(tmp_path / "x.mcap", 400, compression=compression, chunk_size=3000)
    raw = sample.path.read_bytes()
    chunks = _mcap_chunks(sample.path)
    assert len(chunks) >= 5
    victim = chunks[2]
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(raw[:victim] + bytes(30) + raw[victim + 30 :])
    got, reader = _mcap_messages(bad)
    # Said where: the zeroed record reads as an (empty) record of opcode 0, then what follows
    # does not parse.
    places = [int(n) for d in reader.damage for n in re.findall(r" at (\d+)", d)]
    assert any(victim <= p <= victim + 64 for p in places), reader.damage
    if compression == "none":
        assert got == sample.stream  # only the chunk's header is lost: its records read on
    else:
        missing = [m for m in sample.stream if m not in got]
        times = [m[2] for m in missing]
        assert all(m in sample.stream for m in got) and 0 < len(missing) < 200
        assert missing == [m for m in sample.stream if min(times) <= m[2] <= max(times)]


def test_mcap_a_damaged_record_mid_chunk_hides_nothing_else(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.mcap", 200, compression="none")  # one chunk
    raw = sample.path.read_bytes()
    (chunk,) = _mcap_chunks(sample.path)
    _, _, start, stop = next(mcap_format.records(raw, chunk, len(raw)))
    clen = struct.unpack_from("<I", raw, start + 28)[0]
    inner = start + 40 + clen
    messages = [
        at for at, op, _, _ in mcap_format.records(raw, inner, stop) if op == mcap_format.OP_MESSAGE
    ]
    victim = messages[100]
    # Opcode and length zeroed, and the chunk's CRC (else the chunk fails it and is left out
    # whole): as a writer that computes none leaves it.
    raw = raw[:start] + bytes(_mcap_crc_zeroed(raw, start)) + raw[start + 28 :]
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(raw[:victim] + bytes(9) + raw[victim + 9 :])
    got, reader = _mcap_messages(bad)
    assert got == sample.stream[:100] + sample.stream[101:]
    assert len(reader.damage) == 2 and "the data section's CRC does not match its bytes" in (
        reader.damage
    )
    assert any(d.startswith(f"chunk at {chunk}: ") for d in reader.damage), reader.damage


def _mcap_crc_zeroed(raw: bytes, start: int) -> bytes:
    """A chunk record's fixed fields (times, size, CRC) from ``start``, its CRC zeroed."""
    return raw[start : start + 24] + bytes(4)


def test_mcap_chunk_times_that_disagree_with_the_messages_are_noted(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.mcap", 400, compression="zstd", chunk_size=3000)
    raw = bytearray(sample.path.read_bytes())
    victim = _mcap_chunks(sample.path)[1]
    first = struct.unpack_from("<Q", raw, victim + 9)[0]
    struct.pack_into("<Q", raw, victim + 17, first)  # its end time: its start time
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(raw))
    got, reader = _mcap_messages(bad)
    assert got == sample.stream
    # Only the data section's CRC covers a chunk's header: a whole read finds it.
    assert reader.damage == ["the data section's CRC does not match its bytes"]
    assert any("header says" in n for n in reader.notes), reader.notes


def _mcap_messages(path: Path) -> tuple[list[tuple[str, str, int, bytes]], McapReader]:
    reader = open_bag(path)
    assert isinstance(reader, McapReader)
    with reader:
        got = [(c.topic, c.callerid, t, bytes(d)) for c, t, d in reader.messages()]
    return got, reader


def test_a_chunk_info_that_lists_a_connection_twice(tmp_path: Path) -> None:
    """Found by the long fuzz: one bit turned a chunk info's last connection into another
    one it lists; the chunk's messages of the last were silently left out."""
    sample, raw = _sample(tmp_path, "none")
    info = next(r for r in bag_records(raw) if r[1] == fmt.OP_CHUNK_INFO)
    assert fmt.u32_field(info[2], "count") == 4
    damaged = bytearray(raw)
    damaged[info[3] + 24] ^= 1  # the 4th connection id: 3 -> 2
    bad = tmp_path / "bad.bag"
    bad.write_bytes(bytes(damaged))
    got, reader = _messages_and_reader(bad)
    assert got == sample.stream
    assert any("twice" in n for n in reader.notes), reader.notes


def _runs_bag(path: Path, suffix: str) -> tuple[list[tuple[str, str, int, bytes]], Path]:
    """Two topics in runs of 40 messages, in chunks small enough to hold one topic each."""
    bag = path / f"runs{suffix}"
    stream = []
    with open_writer(bag, chunk_size=1000) as writer:
        conns = [
            writer.add_connection(t, "std_msgs/Int32", INT32_MD5, "int32 data\n", callerid="/c")
            for t in ("/a", "/b")
        ]
        for i in range(400):
            conn = conns[(i // 40) % 2]
            data = struct.pack("<i", i)
            writer.write(conn, i * 1000, data)
            stream.append((conn.topic, conn.callerid, i * 1000, data))
    return stream, bag


def test_a_chunk_info_that_names_another_connection_hides_nothing(tmp_path: Path) -> None:
    stream, bag = _runs_bag(tmp_path, ".bag")
    raw = bag.read_bytes()
    infos = [r for r in bag_records(raw) if r[1] == fmt.OP_CHUNK_INFO]
    only_a = next(r for r in infos if fmt.u32_field(r[2], "count") == 1 and raw[r[3]] == 0)
    damaged = bytearray(raw)
    damaged[only_a[3]] = 1  # its one connection: /a (0) -> /b (1)
    bad = tmp_path / "bad.bag"
    bad.write_bytes(bytes(damaged))
    wanted = [m for m in stream if m[0] == "/a"]
    assert read_stream(bad, topics=["/a"]) == wanted
    with open_bag(bad) as reader:
        list(reader.messages(topics=["/a"]))
        assert any("index" in n for n in reader.notes), reader.notes


def test_an_mcap_chunk_index_that_names_another_channel_hides_nothing(tmp_path: Path) -> None:
    stream, path = _runs_bag(tmp_path, ".mcap")
    raw = bytearray(path.read_bytes())
    footer_at = len(raw) - len(mcap_format.MAGIC) - mcap_format.FOOTER_SIZE
    footer = mcap_format.parse_footer(bytes(raw[footer_at:]))
    assert footer is not None
    flipped = False
    for _, op, start, stop in mcap_format.records(raw, footer.summary_start, footer_at):
        index = mcap_format.parse(op, raw, start, stop)
        # The first chunk of /a's channel (0) alone: its index names /b's (1) instead.
        if isinstance(index, mcap_format.ChunkIndex) and list(index.message_index_offsets) == [0]:
            struct.pack_into("<H", raw, start + 32 + 4, 1)  # after 4 u64 and the map's length
            flipped = True
            break
    assert flipped
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(raw))
    assert read_stream(bad, topics=["/a"]) == [m for m in stream if m[0] == "/a"]


def test_a_chunk_info_that_lists_fewer_connections_than_the_chunk_has(tmp_path: Path) -> None:
    sample, raw = _sample(tmp_path, "none")
    pos, _, fields, data, dlen = next(r for r in bag_records(raw) if r[1] == fmt.OP_CHUNK_INFO)
    # Rewritten whole and consistent, one connection short: only the index records say more.
    short = fmt.encode_record({**fields, "count": fmt.U32.pack(3)}, raw[data : data + dlen - 8])
    bad = tmp_path / "bad.bag"
    bad.write_bytes(raw[:pos] + short + raw[data + dlen :])
    got, reader = _messages_and_reader(bad)
    assert got == sample.stream
    assert any("more index records" in n for n in reader.notes), reader.notes


def _name_another_chunk(raw: bytes, nth: int, other: int) -> tuple[bytes, int, int]:
    """``raw`` with the chunk info of chunk ``nth`` naming chunk ``other``; their positions."""
    chunks = [r[0] for r in bag_records(raw) if r[1] == fmt.OP_CHUNK]
    tag = b"chunk_pos=" + fmt.U64.pack(chunks[nth])
    assert raw.count(tag) == 1
    return raw.replace(tag, b"chunk_pos=" + fmt.U64.pack(chunks[other])), chunks[nth], chunks[other]


@pytest.mark.parametrize("compression", BAG_CASES)
@pytest.mark.parametrize(
    ("nth", "other", "said"),
    [
        (1, 2, "no chunk info names the chunk at {lost}"),
        (-1, -2, "two chunk infos name the chunk at {twice}"),
    ],
)
def test_a_chunk_info_naming_another_chunk_hides_nothing(
    tmp_path: Path, compression: str, nth: int, other: int, said: str
) -> None:
    """Issue 32: one chunk was read twice and the one the chunk info stood for never."""
    sample, raw = _sample(tmp_path, compression)
    damaged, lost, twice = _name_another_chunk(raw, nth, other)
    bad = tmp_path / "bad.bag"
    bad.write_bytes(damaged)
    got, reader = _messages_and_reader(bad)
    assert got == sample.stream
    assert not reader.damage and not reader.indexed
    assert reader.unindexed is not None
    assert said.format(lost=lost, twice=twice) in reader.unindexed
    report = recover(bad, tmp_path / "out.bag")
    assert report.complete and read_stream(tmp_path / "out.bag") == sample.stream


def test_a_last_chunk_that_no_chunk_info_names(tmp_path: Path) -> None:
    """The bag header counts one chunk info fewer: the last chunk lies unnamed before the index."""
    sample, raw = _sample(tmp_path, "none")
    chunks = [r[0] for r in bag_records(raw) if r[1] == fmt.OP_CHUNK]
    count = b"chunk_count=" + fmt.U32.pack(len(chunks))
    assert raw.index(count) < chunks[0]
    bad = tmp_path / "bad.bag"
    bad.write_bytes(raw.replace(count, b"chunk_count=" + fmt.U32.pack(len(chunks) - 1), 1))
    got, reader = _messages_and_reader(bad)
    assert got == sample.stream
    assert reader.unindexed is not None
    assert f"no chunk info names the chunk at {chunks[-1]}" in reader.unindexed


def test_a_chunks_connection_record_unlike_the_index_copy(tmp_path: Path) -> None:
    """Issue 32: ``doctor`` called it clean; ``recover`` keeps the chunk's copy."""
    sample, raw = _sample(tmp_path, "none")
    index_pos = fmt.u64_field(bag_records(raw)[0][2], "index_pos")
    inside = raw.index(b"md5sum=" + INT32_MD5.encode()) + len(b"md5sum=")
    assert inside < index_pos  # the first copy: the chunk's
    other = "0" * 32
    chunk = next(r[0] for r in bag_records(raw) if r[1] == fmt.OP_CHUNK)
    bad = tmp_path / "bad.bag"
    bad.write_bytes(raw[:inside] + other.encode() + raw[inside + 32 :])
    report = doctor(bad)
    assert [f for f in report.findings if "differs" in f] == [
        f"connection 2 (/count): its record in the chunk at {chunk} differs from the one in the"
        f" index (md5sum {other!r} against {INT32_MD5!r}); the one in the index is used"
    ]
    assert report.recover_helps
    assert headers(bad)[2][1]["md5sum"] == INT32_MD5  # a read goes by the index, as rosbag
    done = recover(bad, tmp_path / "out.bag")
    assert done.complete and read_stream(tmp_path / "out.bag") == sample.stream
    assert headers(tmp_path / "out.bag")[2][1]["md5sum"] == other
    assert [n for n in done.notes if "differs" in n] == [
        f"connection 2 (/count): its record in the index differs from the one in the chunk at"
        f" {chunk} (md5sum {INT32_MD5!r} against {other!r}); the one in the chunk at {chunk}"
        " is used"
    ]
