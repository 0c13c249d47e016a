"""convert, filter, compress and decompress over both formats."""

from __future__ import annotations

from pathlib import Path

import pytest

from rostools.bag.formats.access import bag_info, open_bag, open_writer
from rostools.bag.formats.model import BagUsageError, UnsupportedBagError
from rostools.bag.tools import ops
from rostools.bag.tools.options import CopyOptions
from rostools.msgs.expr import ExpressionError
from tests.support.bagdata import (
    STEP_NS,
    STRING_MD5,
    handmade_mcap,
    headers,
    read_stream,
    write_sample,
)


@pytest.mark.parametrize(
    ("first", "second"),
    [("a.mcap", "b.bag"), ("a.bag", "b.mcap"), ("a.mcap", "b.mcap"), ("a.bag", "b.bag")],
)
def test_convert_round_trip(tmp_path: Path, first: str, second: str) -> None:
    sample = write_sample(tmp_path / "src.bag", 300, chunk_size=3000)
    report = ops.convert(sample.path, tmp_path / first)
    assert (report.messages_read, report.messages_written, report.connections) == (300, 300, 4)
    ops.convert(tmp_path / first, tmp_path / second, CopyOptions(compression="lz4"))
    for path in (tmp_path / first, tmp_path / second):
        assert read_stream(path) == sample.stream
        assert headers(path) == headers(sample.path)


def test_convert_keeps_unusual_headers(tmp_path: Path) -> None:
    src = tmp_path / "src.bag"
    writer = open_writer(src)
    conn = writer.add_connection(
        "/renamed",
        "std_msgs/Empty",
        "d41d8cd98f00b204e9800998ecf8427e",
        "",
        extra={"topic": "/original", "tcp_nodelay": "1"},
        absent=frozenset({"latching"}),
    )
    writer.write(conn, 5, b"")
    writer.close()
    ops.convert(src, tmp_path / "a.mcap")
    ops.convert(tmp_path / "a.mcap", tmp_path / "b.bag")
    expected = [
        (
            "/renamed",
            {
                "topic": "/original",
                "tcp_nodelay": "1",
                "type": "std_msgs/Empty",
                "md5sum": "d41d8cd98f00b204e9800998ecf8427e",
                "message_definition": "",
            },
        )
    ]
    assert headers(src) == headers(tmp_path / "b.bag") == expected


def test_convert_refuses_non_ros1_messages(tmp_path: Path) -> None:
    from rostools.bag.formats import mcap_format as fmt

    path = handmade_mcap(tmp_path / "cdr.mcap", "ros2", fmt.encode_channel(1, 0, "/x", "cdr", {}))
    with pytest.raises(UnsupportedBagError, match="cdr"):
        ops.convert(path, tmp_path / "out.bag")
    assert not (tmp_path / "out.bag").exists()


def test_same_file_is_refused(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.bag", 5)
    with pytest.raises(BagUsageError, match="same file"):
        ops.convert(sample.path, sample.path, CopyOptions(overwrite=True))


@pytest.mark.parametrize("out", ["y.mcap", "y.bag"])
def test_progress(tmp_path: Path, out: str) -> None:
    sample = write_sample(tmp_path / "x.bag", 10_000, chunk_size=50_000)
    seen: list[tuple[int, int]] = []
    ops.convert(
        sample.path, tmp_path / out, progress=lambda done, total: seen.append((done, total))
    )
    assert seen[-1] == (10_000, 10_000)
    assert len(seen) > 2
    assert [d for d, _ in seen] == sorted(d for d, _ in seen)
    assert read_stream(tmp_path / out) == sample.stream


@pytest.mark.parametrize("out", ["f.bag", "f.mcap"])
def test_filter_by_topic_and_time(tmp_path: Path, out: str) -> None:
    sample = write_sample(tmp_path / "x.bag", 400)
    lo, hi = 100 * STEP_NS, 200 * STEP_NS
    report = ops.filter(
        sample.path, tmp_path / out, CopyOptions(topics=["/chatter"], start=lo, end=hi)
    )
    expected = [m for m in sample.stream if m[0] == "/chatter" and lo <= m[2] <= hi]
    assert read_stream(tmp_path / out) == expected
    assert report.messages_written == len(expected)
    assert report.connections == 2  # both /chatter publishers, nothing else
    assert bag_info(tmp_path / out).format == out.split(".")[1]


def test_filter_expression_decodes_messages(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.bag", 400)
    expression = "topic == '/count' and m.data % 3 == 0 and t.secs == 0 and t.to_sec() < 1"
    ops.filter(sample.path, tmp_path / "f.bag", CopyOptions(expression=expression))
    expected = [
        m
        for i, m in enumerate(sample.stream)
        if m[0] == "/count" and i % 3 == 0 and m[2] < 1_000_000_000
    ]
    assert read_stream(tmp_path / "f.bag") == expected
    assert expected


def test_filter_without_m_never_decodes(tmp_path: Path) -> None:
    src = tmp_path / "x.bag"
    writer = open_writer(src)
    conn = writer.add_connection("/opaque", "nobody/Knows", "0" * 32, "")
    writer.write(conn, 1, b"not a message of any type")
    writer.close()
    ops.filter(
        src, tmp_path / "f.bag", CopyOptions(expression="topic == '/opaque' and t.nsecs == 1")
    )
    assert read_stream(tmp_path / "f.bag") == [("/opaque", "", 1, b"not a message of any type")]
    with pytest.raises(UnsupportedBagError, match="nobody/Knows"):
        ops.filter(src, tmp_path / "g.bag", CopyOptions(expression="m is not None"))
    assert not (tmp_path / "g.bag").exists()


def test_filter_expression_errors(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.bag", 10)
    with pytest.raises(ExpressionError, match="filter expression 'topic ==' is not a Python"):
        ops.filter(sample.path, tmp_path / "f.bag", CopyOptions(expression="topic =="))
    with pytest.raises(ExpressionError, match="ZeroDivisionError"):
        ops.filter(sample.path, tmp_path / "f.bag", CopyOptions(expression="1 / 0"))
    assert not (tmp_path / "f.bag").exists()


def test_filter_print_shows_every_verdict(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.bag", 8)
    said: list[tuple[bool, object]] = []
    show = ("(topic, m.data) if topic == '/count' else topic", lambda v, x: said.append((v, x)))
    ops.filter(
        sample.path, tmp_path / "f.bag", CopyOptions(expression="topic != '/point'"), show=show
    )
    expected = [
        (m[0] != "/point", (m[0], i) if m[0] == "/count" else m[0])
        for i, m in enumerate(sample.stream)
    ]
    assert said == expected
    with pytest.raises(ExpressionError, match="'1 / 0' failed"):
        ops.filter(sample.path, tmp_path / "g.bag", show=("1 / 0", lambda v, x: None))


@pytest.mark.parametrize(("name", "kind"), [("x.bag", "bz2"), ("x.bag", "lz4"), ("x.mcap", "lz4")])
def test_compress_and_decompress(tmp_path: Path, name: str, kind: str) -> None:
    sample = write_sample(tmp_path / name, 300, compression="none")
    packed = tmp_path / ("packed" + Path(name).suffix)
    plain = tmp_path / ("plain" + Path(name).suffix)
    ops.compress(sample.path, packed, CopyOptions(compression=kind))
    ops.decompress(packed, plain)
    assert [c.compression for c in bag_info(packed).compression] == [kind]
    assert [c.compression for c in bag_info(plain).compression] == ["none"]
    assert read_stream(packed) == read_stream(plain) == sample.stream
    with open_bag(packed) as reader:
        assert reader.format == Path(name).suffix[1:]


def test_mcap_extras_follow_filter_recover_and_compress(tmp_path: Path) -> None:
    from rostools.bag.formats import mcap_format as fmt
    from rostools.bag.formats.mcap_reader import McapReader
    from rostools.bag.formats.mcap_writer import McapWriter
    from rostools.bag.tools.recover import recover

    src = tmp_path / "src.mcap"
    with McapWriter(src) as writer:
        conn = writer.add_connection("/s", "std_msgs/String", STRING_MD5, "string data\n")
        writer.add_extra(fmt.Attachment(15, 1, "calib.yaml", "text/yaml", b"k: 1\n", 0))
        writer.add_extra(fmt.Metadata("robot", {"name": "r2"}))
        for t in (10, 20, 30):
            writer.write(conn, t, b"\x01\x00\x00\x00x")
        writer.add_extra(fmt.Attachment(25, 2, "map.pgm", "image/x-portable-graymap", b"P5", 0))

    def names(path: Path) -> list[str]:
        with McapReader(path) as reader:
            return [r.name for r in reader.extras()]

    assert names(src) == ["calib.yaml", "robot", "map.pgm"]
    cut = ops.filter_bag(src, tmp_path / "cut.mcap", CopyOptions(start=10, end=20))
    assert (cut.extras_copied, cut.extras_left_out) == (2, 1)  # map.pgm was logged at 25
    assert names(tmp_path / "cut.mcap") == ["calib.yaml", "robot"]
    ops.compress(src, tmp_path / "lz4.mcap", CopyOptions(compression="lz4"))
    assert names(tmp_path / "lz4.mcap") == names(src)
    raw = src.read_bytes()
    footer = fmt.parse_footer(raw)
    assert footer is not None
    data_end = footer.summary_start - len(fmt.encode_data_end())  # the summary follows it
    (tmp_path / "unfinished.mcap").write_bytes(raw[:data_end])
    recover(tmp_path / "unfinished.mcap", tmp_path / "recovered.mcap")
    assert names(tmp_path / "recovered.mcap") == names(src)


def test_streaming_reads_hand_mapped_pages_back() -> None:
    """A 2 GB bag read from end to end kept 1.9 GB of mapped pages: RSS grew with the file."""
    import mmap

    from rostools.bag.formats.base import FORGET_STEP, Forgetting

    calls: list[tuple[int, int, int]] = []

    class Map:
        def madvise(self, option: int, start: int, length: int) -> None:
            calls.append((option, start, length))

    forget = Forgetting(Map())  # type: ignore[arg-type]
    forget.up_to(FORGET_STEP - 1)
    assert calls == []
    forget.up_to(FORGET_STEP + 4097)
    assert calls == [(mmap.MADV_DONTNEED, 0, FORGET_STEP + 4096)]
    forget.up_to(10)  # a second pass from the front: start counting again there
    forget.up_to(FORGET_STEP + 10)
    assert calls[-1] == (mmap.MADV_DONTNEED, 0, FORGET_STEP)


def test_reading_a_big_bag_keeps_rss_flat(tmp_path: Path) -> None:
    """The peak RSS of a process that reads a 64 MB bag grows by the step, not by the file."""
    import subprocess
    import sys

    from rostools.bag.formats.access import open_writer
    from rostools.bag.formats.base import FORGET_STEP

    path = tmp_path / "big.bag"
    payload = bytes(1_000_000)
    with open_writer(path) as writer:
        conn = writer.add_connection("/b", "std_msgs/String", "992ce8a1687cec8c8bd883ec73ca41d1",
                                     "string data\n")  # fmt: skip
        for i in range(64):
            writer.write(conn, i, len(payload).to_bytes(4, "little") + payload)
    script = (
        "import sys, zlib\n"
        "from rostools.bag.formats.access import open_bag\n"
        "def hwm():\n"
        "    for line in open('/proc/self/status'):\n"
        "        if line.startswith('VmHWM'): return int(line.split()[1]) * 1024\n"
        "with open_bag(sys.argv[1]) as bag:\n"
        "    before = hwm()\n"
        "    for _, _, data in bag.messages(): zlib.crc32(data)  # touches every page\n"
        "    print(hwm() - before)\n"
    )
    done = subprocess.run([sys.executable, "-c", script, str(path)], capture_output=True,
                          text=True, check=True, timeout=60)  # fmt: skip
    assert int(done.stdout) < FORGET_STEP + 16_000_000, done.stdout  # the file is 64 MB
