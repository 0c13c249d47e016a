"""``--rename`` and ``--rename-type`` on ``bag convert`` and ``bag filter`` (issue 15)."""

from __future__ import annotations

from pathlib import Path

import pytest

from rostools.bag.formats.access import open_bag, open_writer
from rostools.msgs.store import TypeStore
from tests.support.bagdata import read_stream, write_sample
from tests.support.env import needs_ros1, run_cli, run_system_python


def _topics(path: Path) -> dict[str, str]:
    with open_bag(path) as bag:
        return {c.topic: c.type for c in bag.connections}


@pytest.mark.parametrize("suffix", ["mcap", "bag"])
def test_convert_renames_topics_and_types(tmp_path: Path, suffix: str) -> None:
    src = write_sample(tmp_path / "s.bag", 400).path
    out = tmp_path / f"out.{suffix}"
    done = run_cli(
        "bag", "convert", str(src), str(out), "--rename", "/chatter:=/talk",
        "--rename", "/point:=/robot/point", "--rename-type", "std_msgs/Int32:=my_msgs/Count",
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert _topics(out) == {
        "/talk": "std_msgs/String", "/count": "my_msgs/Count", "/robot/point": "geometry_msgs/Point"
    }  # fmt: skip
    # Message for message the same publishers, bytes and times; only the names changed.
    names = {"/chatter": "/talk", "/point": "/robot/point", "/count": "/count"}
    assert read_stream(out) == [(names[t], c, ts, d) for t, c, ts, d in read_stream(src)]


def test_filter_selects_by_the_input_names(tmp_path: Path) -> None:
    src = write_sample(tmp_path / "s.bag", 400).path
    out = tmp_path / "f.bag"
    done = run_cli("bag", "filter", str(src), str(out), "topic == '/count'", "--rename",
                   "/count:=/n")  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert _topics(out) == {"/n": "std_msgs/Int32"}


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--rename", "/a"], "give OLD:=NEW"),
        (["--rename", "/a:=b c"], "is not a global topic name"),
        (["--rename", "/a:=/b", "--rename", "/a:=/c"], "/a is renamed twice"),
        (["--rename-type", "Int32:=x/Y"], "is not a package/Type"),
        (["--rename-type", "std_msgs/Header:=my_msgs/Header"], "definition unresolved"),
    ],
)
def test_bad_rules_are_one_line_usage_errors(tmp_path: Path, args: list[str], words: str) -> None:
    src = tmp_path / "stamped.bag"
    store = TypeStore.default()
    with open_writer(src) as writer:
        kind = "geometry_msgs/PointStamped"
        conn = writer.add_connection("/p", kind, store.md5(kind), store.full_text(kind))
        writer.write(conn, 1_000_000_000, bytes(4 + 8 + 4 + 24))
    done = run_cli("bag", "convert", str(src), str(tmp_path / "o.mcap"), *args)
    assert done.returncode == 2 and words in done.stderr and "Traceback" not in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1
    assert not (tmp_path / "o.mcap").exists()


@needs_ros1
def test_rosbag_reads_a_renamed_bag(tmp_path: Path) -> None:
    src = write_sample(tmp_path / "s.bag", 40).path
    out = tmp_path / "r.bag"
    args = ["--rename", "/chatter:=/talk", "--rename-type", "std_msgs/Int32:=my_msgs/Count"]
    assert run_cli("bag", "convert", str(src), str(out), *args).returncode == 0
    script = (
        "import rosbag, sys\n"
        "for topic, msg, t in rosbag.Bag(sys.argv[1]).read_messages():\n"
        "    print(topic, msg._type)\n"
    )
    stdout = run_system_python(script, str(out))
    lines = set(stdout.splitlines())
    assert {"/talk std_msgs/String", "/count my_msgs/Count"} <= lines
