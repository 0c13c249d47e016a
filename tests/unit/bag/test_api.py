"""Opening by content, and the one-line errors for things that are not bags."""

from __future__ import annotations

from pathlib import Path

import pytest

from rostools.bag.formats import rosbag1_format as bagfmt
from rostools.bag.formats.access import detect_format, format_for_name, open_bag
from rostools.bag.formats.connections import read_connections
from rostools.bag.formats.model import BagFormatError, UnsupportedBagError
from rostools.errors import InvalidDataError, NotFoundError, RostoolsError
from tests.support.bagdata import write_sample


def test_format_comes_from_content_not_name(tmp_path: Path) -> None:
    mcap = write_sample(tmp_path / "x.mcap", 5).path
    disguised = tmp_path / "really-mcap.bag"
    disguised.write_bytes(mcap.read_bytes())
    assert detect_format(disguised) == "mcap"
    with open_bag(disguised) as reader:
        assert reader.format == "mcap"
    assert format_for_name("out.MCAP") == "mcap"
    assert format_for_name("out.bag") == format_for_name("out") == "bag"


@pytest.mark.parametrize(
    ("content", "error", "words"),
    [
        (b"", BagFormatError, "empty"),
        (b"hello, I am a text file\n", BagFormatError, "neither"),
        (b"SQLite format 3\x00" + bytes(100), BagFormatError, "SQLite"),
        (b"#ROSBAG V1.2\n" + bytes(100), UnsupportedBagError, "1.2"),
    ],
)
def test_not_a_bag(tmp_path: Path, content: bytes, error: type[Exception], words: str) -> None:
    path = tmp_path / "x.bag"
    path.write_bytes(content)
    with pytest.raises(error, match=words) as caught:
        open_bag(path)
    assert "\n" not in str(caught.value)
    assert isinstance(caught.value, InvalidDataError)


def test_missing_file_and_directory(tmp_path: Path) -> None:
    with pytest.raises(NotFoundError, match="no such file"):
        open_bag(tmp_path / "nope.bag")
    (tmp_path / "ros2bag").mkdir()
    (tmp_path / "ros2bag" / "metadata.yaml").write_text("rosbag2_bagfile_information: {}\n")
    with pytest.raises(BagFormatError, match="ROS 2 bag folder"):
        open_bag(tmp_path / "ros2bag")


def test_cut_bag_header_is_an_error(tmp_path: Path) -> None:
    raw = write_sample(tmp_path / "x.bag", 5).path.read_bytes()
    path = tmp_path / "cut.bag"
    for cut in (13, 20, 100, 4000):
        path.write_bytes(raw[:cut])
        with pytest.raises(BagFormatError):
            open_bag(path)


def test_placeholder_header_without_chunks_is_an_error(tmp_path: Path) -> None:
    header = bagfmt.encode_header(
        {"op": b"\x03", "index_pos": bagfmt.U64.pack(10**9), "conn_count": b"\0" * 4}
    )
    path = tmp_path / "dummy.bag"
    path.write_bytes(bagfmt.MAGIC + bagfmt.U32.pack(len(header)) + header + bagfmt.U32.pack(0))
    with pytest.raises(BagFormatError, match="unindexed"):
        open_bag(path)


def test_bad_mcap(tmp_path: Path) -> None:
    path = tmp_path / "x.mcap"
    path.write_bytes(b"\x89MCAP0\r\n" + b"\x01\xff\xff")
    with pytest.raises(BagFormatError, match="cut short"):
        open_bag(path)


def test_read_connections(tmp_path: Path) -> None:
    for name in ("x.bag", "x.mcap"):
        conns = read_connections(write_sample(tmp_path / name, 5).path)
        assert [c.type for c in conns] == [
            "std_msgs/String",
            "std_msgs/String",
            "std_msgs/Int32",
            "geometry_msgs/Point",
        ]


def test_every_error_is_a_rostools_error(tmp_path: Path) -> None:
    path = tmp_path / "garbage.bag"
    path.write_bytes(bagfmt.MAGIC + b"\xff" * 300)
    with pytest.raises(RostoolsError):
        open_bag(path)
