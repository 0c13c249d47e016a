"""MCAP CRCs are checked by every command that reads messages (issue 32, item 3).

One payload byte flipped in an uncompressed chunk of a file the ``mcap`` package wrote: that
package refuses the file; cat, echo -b, info --freq, convert, filter, recover, merge, split,
compress and decompress left it unsaid (exit 0), and convert and recover wrote the corrupted
message under a fresh, valid CRC. Now each leaves the chunk out, says so, and exits 6, and
what it writes is what the ``mcap`` package, CRCs checked, reads back as intact.
"""

from __future__ import annotations

import json
import struct
from pathlib import Path

import pytest

from rostools.bag.formats import mcap_format as fmt
from tests.support.env import run_cli

DATA_LOSS = 6
STRING_MD5 = "992ce8a1687cec8c8bd883ec73ca41d1"
COUNT = 300


def _text(i: int) -> bytes:
    text = b"hello %d" % i
    return struct.pack("<I", len(text)) + text


def their_file(path: Path, times: list[int] | None = None) -> Path:
    """COUNT std_msgs/String messages written by the ``mcap`` package, uncompressed chunks.

    With the data section's CRC, which it leaves out (0) unless asked.
    """
    from mcap.writer import CompressionType, Writer

    with path.open("wb") as f:
        writer = Writer(f, compression=CompressionType.NONE, chunk_size=2000, enable_data_crcs=True)
        writer.start("ros1", "test")
        schema = writer.register_schema("std_msgs/String", "ros1msg", b"string data\n")
        channel = writer.register_channel("/chatter", "ros1", schema, {"md5sum": STRING_MD5})
        for i, t in enumerate(times or [i * 1000 for i in range(COUNT)]):
            writer.add_message(channel, t, _text(i), t, i)
        writer.finish()
    return path


def chunks(raw: bytes) -> list[tuple[int, int, int]]:
    """(record, content start, end) of each chunk record."""
    found = []
    for rec, op, start, stop in fmt.records(raw, len(fmt.MAGIC), len(raw)):
        if op == fmt.OP_DATA_END:
            break
        if op == fmt.OP_CHUNK:
            found.append((rec, start, stop))
    return found


def chunk_messages(raw: bytes, start: int, stop: int) -> list[tuple[int, int]]:
    """(record, data start) of the message records of the uncompressed chunk at ``start``."""
    (clen,) = struct.unpack_from("<I", raw, start + 28)
    inner = start + 40 + clen
    return [(at, s + 22) for at, op, s, _ in fmt.records(raw, inner, stop) if op == 5]


def theirs(path: Path) -> list[tuple[int, bytes]]:
    """(log time, data) of each message as the ``mcap`` package reads it, CRCs checked.

    Both its readers: the seeking one checks chunk CRCs, the streaming one the data
    section's too.
    """
    from mcap.reader import make_reader
    from mcap.records import Message
    from mcap.stream_reader import StreamReader

    with path.open("rb") as f:
        got = [
            (m.log_time, m.data) for _, _, m in make_reader(f, validate_crcs=True).iter_messages()
        ]
    with path.open("rb") as f:
        records = list(StreamReader(f, validate_crcs=True).records)
    assert sorted((r.log_time, r.data) for r in records if isinstance(r, Message)) == sorted(got)
    return got


@pytest.fixture
def flipped(tmp_path: Path) -> tuple[Path, int, list[tuple[int, bytes]]]:
    """A flipped payload byte in the second chunk: (file, the chunk's place, intact messages)."""
    from mcap.stream_reader import CRCValidationError

    good = their_file(tmp_path / "good.mcap")
    raw = bytearray(good.read_bytes())
    rec, start, stop = chunks(bytes(raw))[1]
    lost = chunk_messages(bytes(raw), start, stop)
    raw[lost[0][1] + 6] ^= 0x10  # a byte of the first message's text: every record still parses
    bad = tmp_path / "flipped.mcap"
    bad.write_bytes(bytes(raw))
    every = theirs(good)
    assert len(every) == COUNT and len(lost) > 1
    with bad.open("rb") as f, pytest.raises(CRCValidationError):
        from mcap.reader import make_reader

        list(make_reader(f, validate_crcs=True).iter_messages())
    times = {struct.unpack_from("<Q", raw, at + 15)[0] for at, _ in lost}
    return bad, rec, [m for m in every if m[0] not in times]


def said(rec: int, lost: int) -> str:
    return f"chunk at {rec}: its CRC does not match its records; its {lost} messages are left out"


def test_every_reading_command_leaves_a_chunk_that_fails_its_crc_out(
    tmp_path: Path, flipped: tuple[Path, int, list[tuple[int, bytes]]]
) -> None:
    bad, rec, intact = flipped
    line = said(rec, COUNT - len(intact))
    out = {name: tmp_path / f"{name}.mcap" for name in ("c", "f", "r", "m", "s")}
    runs = {
        "cat": ["bag", "cat", str(bad), "--raw"],
        "echo": ["topic", "echo", "-b", str(bad), "/chatter", "-F", "json"],
        "info": ["bag", "info", str(bad), "--freq"],
        "convert": ["bag", "convert", str(bad), str(out["c"]), "-c", "none"],
        "filter": ["bag", "filter", str(bad), str(out["f"]), "True"],
        "recover": ["bag", "recover", str(bad), str(out["r"])],
        "merge": ["bag", "merge", str(out["m"]), str(bad)],
        "split": ["bag", "split", str(bad), "--duration", "10", "-o", str(out["s"])],
    }
    for name, args in runs.items():
        done = run_cli(*args)
        assert done.returncode == DATA_LOSS, (name, done.stderr)
        assert line in done.stderr and "Traceback" not in done.stderr, (name, done.stderr)
        errors = [e for e in done.stderr.splitlines() if e.startswith("rostools: ")]
        assert len(errors) == 1, (name, done.stderr)
    cat = run_cli(*runs["cat"])
    assert [json.loads(x)["log_time"] for x in cat.stdout.splitlines()] == [t for t, _ in intact]
    # What is written is what is intact, under CRCs the mcap package checks.
    for name in ("c", "f", "r", "m"):
        assert theirs(out[name]) == intact, name
    assert theirs(tmp_path / "s_0.mcap") == intact
    for verb in ("compress", "decompress"):
        copy = tmp_path / f"{verb}.mcap"
        copy.write_bytes(bad.read_bytes())
        done = run_cli("bag", verb, str(copy))
        assert done.returncode == DATA_LOSS and line in done.stderr, (verb, done.stderr)
        assert theirs(copy) == intact
    doctor = run_cli("bag", "doctor", str(bad))
    assert doctor.returncode == 1 and line in doctor.stdout, doctor.stdout


def test_no_crc_check_reads_the_chunk_as_it_is(
    tmp_path: Path, flipped: tuple[Path, int, list[tuple[int, bytes]]]
) -> None:
    bad, _, _ = flipped
    cat = run_cli("bag", "cat", str(bad), "--raw", "--no-crc-check")
    assert cat.returncode == 0 and not cat.stderr, cat.stderr
    assert len(cat.stdout.splitlines()) == COUNT
    for args in (
        ["bag", "convert", str(bad), str(tmp_path / "c.mcap"), "--no-crc-check"],
        ["topic", "echo", "-b", str(bad), "/chatter", "--no-crc-check"],
    ):
        done = run_cli(*args)
        assert done.returncode == 0, (args, done.stderr)
    assert len(theirs(tmp_path / "c.mcap")) == COUNT
    done = run_cli("topic", "echo", "/chatter", "--no-crc-check")
    assert done.returncode == 2 and "--no-crc-check needs --bag" in done.stderr, done.stderr


def test_a_whole_read_checks_the_data_section_crc(tmp_path: Path) -> None:
    """A byte outside every chunk (a message index), in a file whose chunks are out of time
    order: the read puts the data section's CRC together from pieces as they come."""
    times = [(COUNT - 1 - i // 40) * 100_000 + i % 40 for i in range(COUNT)]  # runs backwards
    good = their_file(tmp_path / "good.mcap", times)
    raw = bytearray(good.read_bytes())
    done = run_cli("bag", "cat", str(good), "--raw")
    assert done.returncode == 0 and not done.stderr, done.stderr
    assert len(done.stdout.splitlines()) == COUNT
    _, _, stop = chunks(bytes(raw))[0]
    assert raw[stop] == fmt.OP_MESSAGE_INDEX  # the first chunk's message index follows it
    raw[stop + 9 + 2 + 4 + 3] ^= 0x01  # a byte of its first entry's time
    bad = tmp_path / "bad.mcap"
    bad.write_bytes(bytes(raw))
    done = run_cli("bag", "cat", str(bad), "--raw")
    assert done.returncode == DATA_LOSS, done.stderr
    assert "the data section's CRC does not match its bytes" in done.stderr
    assert len(done.stdout.splitlines()) == COUNT  # no chunk is in doubt: every message read
    # Reading part of the file reads only part of the data section: no check.
    part = run_cli("bag", "cat", str(bad), "--raw", "--start", "0.00001")
    assert part.returncode == 0, part.stderr


def test_the_api_reads_what_is_intact_then_says_what_it_left_out(
    flipped: tuple[Path, int, list[tuple[int, bytes]]],
) -> None:
    # rostools.read_bag gave the intact messages and ended as if the file were whole.
    import rostools

    bad, rec, intact = flipped
    got = []
    with pytest.raises(rostools.DataLossError) as caught:
        for message in rostools.read_bag(bad):
            got.append(message.time.to_nsec())
    assert got == [t for t, _ in intact]
    assert said(rec, COUNT - len(intact)) in str(caught.value)
    assert caught.value.exit_code == DATA_LOSS


def test_play_checks_crcs_unless_told_not_to(
    flipped: tuple[Path, int, list[tuple[int, bytes]]],
    rostools_master: str,
    cli_env: dict[str, str],
) -> None:
    bad, rec, intact = flipped
    checked = run_cli("bag", "play", str(bad), "-r", "1000", "-F", "json", env=cli_env)
    assert checked.returncode == DATA_LOSS, checked.stderr
    assert said(rec, COUNT - len(intact)) in checked.stderr
    assert json.loads(checked.stdout) == {"published": len(intact)}
    done = run_cli(
        "bag", "play", str(bad), "-r", "1000", "--no-crc-check", "-F", "json", env=cli_env
    )
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout) == {"published": COUNT}
