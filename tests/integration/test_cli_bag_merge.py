"""``bag merge`` (issue 15): several bags into one, in time order, connections deduplicated."""

from __future__ import annotations

import json
import struct
from pathlib import Path

from rostools.bag.formats.access import open_bag, open_writer
from tests.support.bagdata import STRING_MD5, read_stream, write_sample
from tests.support.env import needs_ros1, run_cli, run_system_python


def _other(path: Path, count: int) -> list[tuple[str, str, int, bytes]]:
    """/other, std_msgs/String, at times between the sample's: (topic, callerid, t, data)."""
    stream = []
    with open_writer(path) as writer:
        conn = writer.add_connection("/other", "std_msgs/String", STRING_MD5, "string data\n",
                                     callerid="/other_node")  # fmt: skip
        for i in range(count):
            data = struct.pack("<I", 1) + b"o"
            t = i * 2_000_000 + 500_000
            writer.write(conn, t, data)
            stream.append(("/other", "/other_node", t, data))
    return stream


def test_merge_interleaves_and_dedups(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "a.bag", 400)
    other = _other(tmp_path / "b.mcap", 150)
    out = tmp_path / "m.mcap"
    done = run_cli("bag", "merge", str(out), str(sample.path), str(tmp_path / "b.mcap"),
                   str(sample.path), "-F", "json")  # fmt: skip
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout.splitlines()[-1])
    assert report["messages_written"] == 950 and report["connections"] == 5
    # Time order; on equal times the inputs' order, so a.bag's copy comes before its twin.
    expected = sorted(sample.stream * 2 + other, key=lambda m: m[2])
    assert read_stream(out) == expected
    from mcap.reader import make_reader

    with out.open("rb") as f:  # the mcap library reads what we wrote, in the same order
        theirs = [(c.topic, m.log_time) for _, c, m in make_reader(f).iter_messages()]
    assert theirs == [(m[0], m[2]) for m in expected]
    with open_bag(out) as bag:
        assert sorted(c.callerid for c in bag.connections) == [
            "/counter", "/other_node", "/pointer", "/talker", "/talker2"
        ]  # fmt: skip


def test_merge_filters_and_renames(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "a.bag", 400)
    _other(tmp_path / "b.bag", 150)
    out = tmp_path / "m.bag"
    done = run_cli("bag", "merge", str(out), str(sample.path), str(tmp_path / "b.bag"),
                   "-t", "/count", "-t", "/other", "--filter", "t.to_sec() < 0.2",
                   "--rename", "/other:=/o", "-q")  # fmt: skip
    assert done.returncode == 0, done.stderr
    got = read_stream(out)
    assert {m[0] for m in got} == {"/count", "/o"} and all(m[2] < 200_000_000 for m in got)
    assert [m[2] for m in got] == sorted(m[2] for m in got)


def test_two_types_for_one_topic_are_refused_before_writing(tmp_path: Path) -> None:
    write_sample(tmp_path / "a.bag", 40)
    with open_writer(tmp_path / "b.bag") as writer:
        conn = writer.add_connection("/count", "std_msgs/String", STRING_MD5, "string data\n")
        writer.write(conn, 1, struct.pack("<I", 0))
    out = tmp_path / "m.bag"
    done = run_cli("bag", "merge", str(out), str(tmp_path / "a.bag"), str(tmp_path / "b.bag"))
    assert done.returncode == 2 and "Traceback" not in done.stderr
    assert "topic /count is std_msgs/Int32 in" in done.stderr and "std_msgs/String in" in (
        done.stderr
    )
    assert not out.exists()


@needs_ros1
def test_rosbag_reads_a_merged_bag_in_order(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "a.bag", 200)
    other = _other(tmp_path / "b.mcap", 100)
    out = tmp_path / "m.bag"
    assert (
        run_cli("bag", "merge", str(out), str(tmp_path / "b.mcap"), str(sample.path)).returncode
        == 0
    )
    script = (
        "import rosbag, sys\n"
        "for topic, msg, t in rosbag.Bag(sys.argv[1]).read_messages(raw=True):\n"
        "    print(topic, t.to_nsec())\n"
    )
    stdout = run_system_python(script, str(out))
    expected = sorted(other + sample.stream, key=lambda m: m[2])
    assert [line.split()[1] for line in stdout.splitlines()] == [str(m[2]) for m in expected]
