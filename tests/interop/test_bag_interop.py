"""Our .bag files against the real ROS 1 rosbag (Debian): read, info, reindex, and back."""

from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path
from typing import Any

import pytest
import yaml

from rostools.bag.formats.access import bag_info
from rostools.bag.tools import ops
from rostools.bag.tools.options import CopyOptions
from rostools.bag.tools.recover import recover
from tests.support.bagdata import digest, first_chunk_data, headers, read_stream, write_sample
from tests.support.env import CLI, SYSTEM_PYTHON, needs_ros1, run_system_python

pytestmark = [pytest.mark.interop, needs_ros1]

DUMP = Path(__file__).parent.parent / "support" / "rosbag_dump.py"


def rosbag_view(*paths: Path) -> dict[str, Any]:
    proc = subprocess.run(
        [SYSTEM_PYTHON, str(DUMP), *map(str, paths)],
        capture_output=True,
        text=True,
        timeout=300,
        check=True,
    )
    views = json.loads(proc.stdout)
    return {p: views[str(p)] for p in paths}  # type: ignore[misc]


def as_rosbag_sees(path: Path) -> tuple[list[list[Any]], list[list[Any]]]:
    """Our reading of a bag in the shape of rosbag_dump's (stream, headers)."""
    stream = [[topic, t, digest(data)] for topic, _, t, data in read_stream(path)]
    return stream, [[topic, header] for topic, header in headers(path)]


@pytest.mark.parametrize("compression", ["none", "bz2", "lz4"])
def test_rosbag_reads_our_bags(tmp_path: Path, compression: str) -> None:
    sample = write_sample(tmp_path / "ours.bag", 3000, compression=compression, chunk_size=20_000)
    view = rosbag_view(sample.path)[sample.path]
    assert "error" not in view, view
    stream, conn_headers = as_rosbag_sees(sample.path)
    assert view["stream"] == stream
    assert view["headers"] == conn_headers
    info = view["info"]
    assert info["messages"] == 3000
    assert info["compression"] == compression
    assert info["indexed"] is True
    assert {t["topic"]: (t["messages"], t.get("connections", 1)) for t in info["topics"]} == {
        "/chatter": (1500, 2),
        "/count": (750, 1),
        "/point": (750, 1),
    }


def test_rosbag_info_cli(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "ours.bag", 500, compression="lz4")
    proc = subprocess.run(
        ["rosbag", "info", "--yaml", str(sample.path)], capture_output=True, text=True, check=True
    )
    info = yaml.safe_load(proc.stdout)
    ours = bag_info(sample.path)
    assert info["messages"] == ours.message_count
    assert info["compressed"] == ours.compressed_size
    assert info["uncompressed"] == ours.uncompressed_size


@pytest.mark.parametrize("compression", ["none", "lz4"])
def test_rosbag_reindex_of_our_unclosed_bag(tmp_path: Path, compression: str) -> None:
    sample = write_sample(
        tmp_path / "rec.bag", 2000, compression=compression, chunk_size=20_000, close=False
    )
    copy = tmp_path / "copy.bag"
    shutil.copy(sample.path, copy)
    subprocess.run(["rosbag", "reindex", "-q", str(copy)], capture_output=True, check=True)
    view = rosbag_view(copy)[copy]
    assert "error" not in view, view
    theirs = view["stream"]
    full = [[topic, t, digest(data)] for topic, _, t, data in sample.stream]
    # rosbag reindex keeps the closed chunks (our 4117-byte header layout survives its rewrite)
    # and drops the chunk that was still open; our recover keeps every record.
    assert theirs == full[: len(theirs)]
    assert len(theirs) > 1000
    report = recover(sample.path, tmp_path / "ours.bag")
    assert report.messages == 2000
    if compression == "none":
        assert len(theirs) < 2000


def test_rosbag_reindex_keeps_a_closed_bag(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "x.bag", 500, compression="bz2", chunk_size=10_000)
    subprocess.run(["rosbag", "reindex", "-q", str(sample.path)], capture_output=True, check=True)
    assert read_stream(sample.path) == sample.stream


def test_reindex_takes_what_rosbag_reindex_takes(tmp_path: Path) -> None:
    """Several bags, -q, in place with x.orig.bag kept: the same files as rosbag's (issue 13)."""
    sample = write_sample(tmp_path / "s.bag", 300, close=False)
    trees = {}
    for tool in ("rosbag", "rostools"):
        work = tmp_path / tool
        work.mkdir()
        names = [work / "a.bag", work / "b.bag"]
        for name in names:
            shutil.copy(sample.path, name)
        cmd = ["rosbag"] if tool == "rosbag" else [*CLI, "bag"]
        subprocess.run([*cmd, "reindex", "-q", *map(str, names)], capture_output=True, check=True)
        trees[tool] = sorted(p.name for p in work.iterdir())
        view = rosbag_view(*names)
        assert all("error" not in view[n] for n in names), view
    assert trees["rostools"] == trees["rosbag"] == ["a.bag", "a.orig.bag", "b.bag", "b.orig.bag"]


WRITE_WITH_ROSBAG = r"""
import sys, rosbag, genpy
from std_msgs.msg import String, Int32
path, compression = sys.argv[1], sys.argv[2]
with rosbag.Bag(path, "w", compression=compression, chunk_threshold=4096) as bag:
    for i in range(500):
        bag.write("/s", String(data="m%d" % i), genpy.Time(i, 7))
        hdr = {"topic": "/i", "type": "std_msgs/Int32", "md5sum": Int32._md5sum,
               "message_definition": Int32._full_text, "callerid": "/pub", "latching": "1"}
        bag.write("/i", Int32(data=i), genpy.Time(i, 9), connection_header=hdr)
"""


@pytest.mark.parametrize("compression", ["none", "bz2", "lz4"])
def test_we_read_bags_rosbag_writes(tmp_path: Path, compression: str) -> None:
    path = tmp_path / "theirs.bag"
    run_system_python(WRITE_WITH_ROSBAG, str(path), compression)
    view = rosbag_view(path)[path]
    stream, conn_headers = as_rosbag_sees(path)
    assert stream == view["stream"]
    assert conn_headers == view["headers"]
    info = bag_info(path)
    assert info.message_count == 1000
    assert info.compression[0].compression == compression
    latched = [c for c in info.connections if c.topic == "/i"]
    assert latched[0].latching and latched[0].callerid == "/pub"


def test_convert_round_trip_is_read_by_rosbag(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "a.bag", 1000, compression="lz4")
    ops.convert(sample.path, tmp_path / "b.mcap")
    ops.convert(tmp_path / "b.mcap", tmp_path / "c.bag", CopyOptions(compression="bz2"))
    views = rosbag_view(sample.path, tmp_path / "c.bag")
    assert views[sample.path]["stream"] == views[tmp_path / "c.bag"]["stream"]
    assert views[sample.path]["headers"] == views[tmp_path / "c.bag"]["headers"]


def test_we_salvage_a_cut_lz4_chunk_that_rosbag_reindex_drops(tmp_path: Path) -> None:
    """A real rosbag lz4 bag cut inside its one chunk: reindex keeps nothing, recover half."""
    path = tmp_path / "theirs.bag"
    run_system_python(WRITE_ONE_CHUNK, str(path))
    full = rosbag_view(path)[path]["stream"]
    raw = path.read_bytes()
    start, length = first_chunk_data(raw)
    cut = tmp_path / "cut.bag"
    cut.write_bytes(raw[: start + length // 2])
    theirs = tmp_path / "reindexed.bag"
    shutil.copy(cut, theirs)
    subprocess.run(["rosbag", "reindex", "-q", str(theirs)], capture_output=True, check=False)
    their_view = rosbag_view(theirs)[theirs]
    assert their_view.get("stream", []) == []  # rosbag throws the cut chunk away
    report = recover(cut, tmp_path / "ours.bag")
    view = rosbag_view(tmp_path / "ours.bag")[tmp_path / "ours.bag"]
    assert view["stream"] == full[: len(view["stream"])]
    assert 0.3 * len(full) < report.messages == len(view["stream"]) < len(full)


WRITE_ONE_CHUNK = r"""
import sys, rosbag, genpy
from std_msgs.msg import String
with rosbag.Bag(sys.argv[1], "w", compression="lz4") as bag:
    for i in range(3000):
        bag.write("/s", String(data="message %d of a recording" % i), genpy.Time(i, 7))
"""
