"""``bag convert --to ros2`` (issue 39): ROS 1 bags into rosbag2 that ros2 bag plays.

Synthetic bags (every builtin type, nested and fixed arrays, constants, empty messages, and
Noetic types whose ROS 2 twins differ): rosbags' rosbag2 reader reads our output, every message
equals the ROS 1 one less ``seq``, its CDR bytes equal rosbags-convert's, the mcap package
checks every CRC, and metadata.yaml has rosbag2's fields (``tests/support/ros2conv.py``).
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest
import yaml

from rostools.bag.formats.access import open_writer
from tests.support.env import run_cli
from tests.support.ros2conv import (
    check_output,
    ros2_messages,
    rosbags_convert,
    same_less_seq,
    synthetic_bag,
)

LATCHED = {"/scalars", "/camera_info"}


@pytest.fixture(scope="module")
def bags(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    """Two synthetic bags of other random messages, the second one later."""
    folder = tmp_path_factory.mktemp("ros2conv")
    paths = [folder / "a.bag", folder / "b.bag"]
    synthetic_bag(paths[0], count=5, seed=1)
    synthetic_bag(paths[1], count=3, seed=2, t0=10**18 + 10**9)
    return paths


def _qos(entry: dict[str, object]) -> object:
    return entry["topic_metadata"]["offered_qos_profiles"]  # type: ignore[index]


def test_two_bags_into_one_rosbag2_as_rosbags_convert_writes(
    bags: list[Path], tmp_path: Path
) -> None:
    out = tmp_path / "out"
    done = run_cli("bag", "convert", *map(str, bags), str(out), "--to", "ros2", "-q")
    assert done.returncode == 0, done.stderr
    assert "wrote 88 of 88 messages" in done.stderr
    assert sorted(p.name for p in out.iterdir()) == ["metadata.yaml", "out_0.mcap"]
    assert check_output(bags, out) == []
    theirs = tmp_path / "theirs"
    rosbags_convert(bags, theirs, "lyrical")
    ours, want = ros2_messages(out), ros2_messages(theirs)
    assert sorted(ours) == sorted(want)
    for topic in want:  # the same CDR bytes, at the same times
        assert ours[topic] == want[topic], topic
    info = yaml.safe_load((out / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert info["version"] == 9 and info["ros_distro"] == "lyrical"
    types = {e["topic_metadata"]["name"]: e for e in info["topics_with_message_count"]}
    assert types["/tf"]["topic_metadata"]["type"] == "tf2_msgs/msg/TFMessage"
    assert types["/arrays"]["topic_metadata"]["type"] == "test_ros2/msg/Arrays"
    for name, entry in types.items():
        durability = "transient_local" if name in LATCHED else "volatile"
        assert [q["durability"] for q in _qos(entry)] == [durability], name  # type: ignore[attr-defined]


def test_humble_writes_its_metadata_version_and_bare_mcap(bags: list[Path], tmp_path: Path) -> None:
    out = tmp_path / "old"
    done = run_cli("bag", "convert", str(bags[1]), str(out), "--to", "ros2", "--distro", "humble")
    assert done.returncode == 0, done.stderr
    assert check_output(bags[1:], out) == []
    info = yaml.safe_load((out / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert info["version"] == 5 and "ros_distro" not in info
    entry = info["topics_with_message_count"][0]
    assert isinstance(_qos(entry), str) and "type_description_hash" not in entry["topic_metadata"]
    theirs = tmp_path / "theirs"
    rosbags_convert(bags[1:], theirs, "humble")
    assert ros2_messages(out) == ros2_messages(theirs)
    bare = tmp_path / "bare.mcap"
    done = run_cli("bag", "convert", str(bags[1]), str(bare), "--to", "ros2", "--distro", "humble")
    assert done.returncode == 0, done.stderr
    assert not (tmp_path / "metadata.yaml").exists()
    from mcap.reader import make_reader

    with bare.open("rb") as f:
        reader = make_reader(f, validate_crcs=True)
        assert reader.get_header().profile == "ros2"
        records = {m.name: m.metadata for m in reader.iter_metadata()}
        assert sum(1 for _ in reader.iter_messages()) == 33
    assert yaml.safe_load(records["rosbag2"]["serialized_metadata"])["message_count"] == 33


def _bag_with(path: Path, topic: str, type_: str, definition: str, data: bytes) -> None:
    with open_writer(path) as writer:
        conn = writer.add_connection(topic, type_, "0" * 32, definition)
        writer.write(conn, 10**9, data)
        good = writer.add_connection(
            "/ok", "std_msgs/UInt8", "7c8164229e7d2c17eb95e9231617fdee", "uint8 data\n"
        )
        writer.write(good, 2 * 10**9, b"\x07")


def test_a_type_ros2_cannot_name_is_refused_before_writing(tmp_path: Path) -> None:
    bag = tmp_path / "in.bag"
    _bag_with(bag, "/odd", "my_pkg/lower_case", "int32 x\n", b"\x01\x00\x00\x00")
    out = tmp_path / "out"
    done = run_cli("bag", "convert", str(bag), str(out), "--to", "ros2")
    assert done.returncode == 1, done.stderr
    assert done.stderr.count("\n") == 1 and "my_pkg/lower_case" in done.stderr
    assert "Traceback" not in done.stderr and not out.exists()
    done = run_cli("bag", "convert", str(bag), str(out), "--to", "ros2", "-x", "/odd")
    assert done.returncode == 0, done.stderr
    assert list(ros2_messages(out)) == ["/ok"]
    rules = tmp_path / "types.yaml"
    rules.write_text("renames:\n  my_pkg/lower_case: my_pkg/msg/Upper\n")
    renamed = tmp_path / "renamed"
    done = run_cli("bag", "convert", str(bag), str(renamed), "--to", "ros2", "--types", str(rules))
    assert done.returncode == 0, done.stderr
    info = yaml.safe_load((renamed / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    assert {e["topic_metadata"]["type"] for e in info["topics_with_message_count"]} == {
        "my_pkg/msg/Upper", "std_msgs/msg/UInt8",
    }  # fmt: skip
    assert check_output([bag], renamed) == []


def test_a_types_file_defines_a_type_ros2_lacks(tmp_path: Path) -> None:
    bag = tmp_path / "in.bag"
    _bag_with(bag, "/pose", "my_pkg/Pose2", "float64 x\nfloat64 y\n", bytes(16))
    rules = tmp_path / "types.yaml"
    # Its ROS 2 definition adds a field: it gets its default, as rosbags-convert gives one.
    rules.write_text(
        "definitions:\n  my_pkg/Pose2: |\n    float64 x\n    float64 y\n    float64 theta\n"
    )
    out = tmp_path / "out"
    done = run_cli("bag", "convert", str(bag), str(out), "--to", "ros2", "--types", str(rules))
    assert done.returncode == 0, done.stderr
    assert ros2_messages(out)["/pose"] == [(10**9, b"\x00\x01\x00\x00" + bytes(24))]
    bad = tmp_path / "bad.yaml"
    bad.write_text("renames: [1, 2]\n")
    done = run_cli(
        "bag", "convert", str(bag), str(tmp_path / "x"), "--to", "ros2", "--types", str(bad)
    )
    assert done.returncode == 2 and "renames" in done.stderr and done.stderr.count("\n") == 1


def test_damage_and_misfit_messages_are_listed_with_exit_6(
    bags: list[Path], tmp_path: Path
) -> None:
    cut = tmp_path / "cut.bag"
    data = bags[0].read_bytes()
    cut.write_bytes(data[: len(data) * 2 // 3])
    out = tmp_path / "out"
    done = run_cli("bag", "convert", str(cut), str(out), "--to", "ros2")
    assert done.returncode == 6, done.stderr
    assert "left out" in done.stderr and "Traceback" not in done.stderr
    assert (out / "metadata.yaml").is_file() and ros2_messages(out)
    short = tmp_path / "short.bag"
    _bag_with(short, "/short", "std_msgs/UInt32", "uint32 data\n", b"\x01\x02")
    done = run_cli("bag", "convert", str(short), str(tmp_path / "s"), "--to", "ros2")
    assert done.returncode == 6, done.stderr
    assert "1 message on /short do not fit std_msgs/UInt32" in done.stderr
    assert list(ros2_messages(tmp_path / "s")) == ["/ok"]


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["--to", "ros3"], "--to takes ros1 or ros2"),
        (["--to", "ros2", "--distro", "rolling"], "unknown ROS 2 distro 'rolling'"),
        (["--distro", "jazzy"], "--distro is for --to ros2"),
        (["--to", "ros2", "--rename", "/a:=/b"], "not for --to ros2"),
    ],
)
def test_bad_options_say_what_in_one_line(
    bags: list[Path], tmp_path: Path, args: list[str], says: str
) -> None:
    done = run_cli("bag", "convert", str(bags[1]), str(tmp_path / "o"), *args)
    assert done.returncode == 2, done.stderr
    assert says in done.stderr and done.stderr.count("\n") == 1
    assert not (tmp_path / "o").exists()


def test_several_inputs_need_to_ros2_and_outputs_are_not_overwritten(
    bags: list[Path], tmp_path: Path
) -> None:
    done = run_cli("bag", "convert", *map(str, bags), str(tmp_path / "o.mcap"))
    assert done.returncode == 2 and "several with --to ros2" in done.stderr
    (tmp_path / "o").mkdir()
    done = run_cli("bag", "convert", str(bags[1]), str(tmp_path / "o"), "--to", "ros2")
    assert done.returncode == 2 and "exists" in done.stderr
    assert os.listdir(tmp_path / "o") == []


def test_the_api_converts_and_the_oracle_sees_a_difference(
    bags: list[Path], tmp_path: Path
) -> None:
    import rostools

    out = rostools.convert_to_ros2(bags[1], tmp_path / "api", distro="jazzy")
    assert out == tmp_path / "api"
    assert check_output(bags[1:], out) == []
    # The oracle is not blind: a seq kept, a value changed, a field missing are all seen.
    header = {"seq": 1, "stamp": {"sec": 1, "nanosec": 2}, "frame_id": "a"}
    assert (
        list(same_less_seq({"h": header}, {"h": {"stamp": header["stamp"], "frame_id": "a"}})) == []
    )
    assert list(same_less_seq({"x": 1.5}, {"x": 1.25})) == [".x: 1.5 != 1.25"]
    assert list(same_less_seq({"x": 1, "D": [1.0]}, {"x": 1})) == [".D: missing in ROS 2"]


def test_an_mcap_of_ros1_messages_converts_as_its_bag(bags: list[Path], tmp_path: Path) -> None:
    mcap = tmp_path / "b.mcap"
    assert run_cli("bag", "convert", str(bags[1]), str(mcap)).returncode == 0
    done = run_cli("bag", "convert", str(mcap), str(tmp_path / "from_mcap"), "--to", "ros2")
    assert done.returncode == 0, done.stderr
    done = run_cli("bag", "convert", str(bags[1]), str(tmp_path / "from_bag"), "--to", "ros2")
    assert done.returncode == 0, done.stderr
    assert ros2_messages(tmp_path / "from_mcap") == ros2_messages(tmp_path / "from_bag")
    # ROS 2 messages in are not ROS 1: refused in one line, nothing written
    again = tmp_path / "again"
    done = run_cli(
        "bag", "convert", str(tmp_path / "from_bag" / "from_bag_0.mcap"), str(again), "--to", "ros2"
    )
    assert done.returncode == 1 and "ROS 2 CDR" in done.stderr and done.stderr.count("\n") == 1
    assert not again.exists()
