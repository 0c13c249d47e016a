"""``topic echo -b`` and ``topic list -b``, set beside rostopic on the same bag (issue 13)."""

from __future__ import annotations

import struct
import subprocess
from pathlib import Path

import pytest

from rostools.bag.access import open_writer
from tests.support.env import needs_ros1, run_cli

pytestmark = [pytest.mark.interop, needs_ros1]

SEP = "=" * 80
POINT_STAMPED_DEF = (
    f"std_msgs/Header header\ngeometry_msgs/Point point\n{SEP}\nMSG: std_msgs/Header\n"
    f"uint32 seq\ntime stamp\nstring frame_id\n{SEP}\nMSG: geometry_msgs/Point\n"
    "float64 x\nfloat64 y\nfloat64 z\n"
)
POINT_STAMPED_MD5 = "c63aecb41bfdfd6b7e1fac37c7cbe7bf"


def test_plot_time_is_the_record_time(tmp_path: Path) -> None:
    """``-p`` writes the bag's record time in %time, not ``header.stamp``, as rostopic does."""
    bag = tmp_path / "h.bag"
    with open_writer(bag) as writer:
        conn = writer.add_connection(
            "/h", "geometry_msgs/PointStamped", POINT_STAMPED_MD5, POINT_STAMPED_DEF
        )
        for i in range(2):
            header = struct.pack("<III", i, 100 + i, 5) + struct.pack("<I", 1) + b"f"
            data = header + struct.pack("<3d", i, 2.5, -1.0)
            writer.write(conn, 200_000_000_000 + i, data)  # recorded 100 s after its stamp
    ours = run_cli("topic", "echo", "-b", str(bag), "-p", "-n", "2", "/h")
    theirs = subprocess.run(
        ["rostopic", "echo", "-b", str(bag), "-p", "-n", "2", "/h"],
        capture_output=True, text=True, timeout=60, check=False,
    )  # fmt: skip
    assert theirs.returncode == 0, theirs.stderr
    assert ours.stdout.splitlines()[1].startswith("200000000000,")  # was 100000000005
    assert ours.stdout == theirs.stdout


def test_list_of_one_topic_counts_its_messages(tmp_path: Path) -> None:
    """``list -b BAG /ns``: rostopic's "N message(s) from ... to ..." (it printed the name)."""
    bag = tmp_path / "l.bag"
    string_md5 = "992ce8a1687cec8c8bd883ec73ca41d1"
    with open_writer(bag) as writer:
        conns = [
            writer.add_connection(t, "std_msgs/String", string_md5, "string data\n")
            for t in ("/ns/a", "/ns/b", "/other")
        ]
        for i in range(30):
            writer.write(conns[i % 3], 1_795_459_893_000_000_000 + i * 7_000_000_000, b"\0\0\0\0")
    for name in ("/ns", "/ns/b"):
        ours = run_cli("topic", "list", "-b", str(bag), name)
        theirs = subprocess.run(
            ["rostopic", "list", "-b", str(bag), name],
            capture_output=True, text=True, timeout=60, check=False,
        )  # fmt: skip
        assert theirs.returncode == 0, theirs.stderr
        assert ours.stdout == theirs.stdout and "message(s) from" in ours.stdout
