"""``bag record --to ros2`` end to end on ``rostools core``: a rosbag2 folder that rosbags reads.

rostools' own publishers: a stamped topic, a latched one, and a custom type that ROS 2 cannot
name (``my_pkg/Odd_Name``: ROS 2 names hold no ``_``), which is left out in one line while the
others are recorded, and exit 6. The real rospy peer is in ``tests/interop``.
"""

from __future__ import annotations

import json
import signal
from pathlib import Path
from typing import Any

import pytest

from rostools.bag.formats.ros2types import DEFAULT_DISTRO
from tests.support.bagdata import recorded
from tests.support.env import run_cli
from tests.support.procs import Proc, start_cli, subscribed, wait_for


def decoded(folder: Path, distro: str = DEFAULT_DISTRO) -> dict[str, list[Any]]:
    """Each topic's messages in a rosbag2 folder, as rosbags' reader decodes them; the
    ``mcap`` package reads the MCAP through, every CRC checked."""
    from mcap.reader import make_reader
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores[f"ROS2_{distro.upper()}"])
    found: dict[str, list[Any]] = {}
    with Reader(folder) as reader:
        for conn, _, raw in reader.messages():
            found.setdefault(conn.topic, []).append(store.deserialize_cdr(raw, conn.msgtype))
    with (folder / f"{folder.name}_0.mcap").open("rb") as f:
        count = sum(1 for _ in make_reader(f, validate_crcs=True).iter_messages())
    assert count == sum(len(m) for m in found.values())
    return found


def durability(folder: Path) -> dict[str, str]:
    """Each topic's offered durability, from metadata.yaml."""
    import yaml

    info = yaml.safe_load((folder / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    return {
        t["topic_metadata"]["name"]: t["topic_metadata"]["offered_qos_profiles"][0]["durability"]
        for t in info["topics_with_message_count"]
    }


def test_record_to_ros2_keeps_everything_on_sigterm_and_leaves_out_what_does_not_map(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    (tmp_path / "types" / "my_pkg" / "msg").mkdir(parents=True)
    (tmp_path / "types" / "my_pkg" / "msg" / "Odd_Name.msg").write_text("int32 x\n")
    env = dict(cli_env, ROSTOOLS_MSG_PATH=str(tmp_path / "types"))
    point = "{header: {frame_id: f}, point: {x: 1.5}}"
    pubs = [
        start_cli("topic", "pub", "-r", "50", "/h", "geometry_msgs/PointStamped", point, env=env),
        start_cli("topic", "pub", "-l", "/latched", "std_msgs/String", "data: kept", env=env),
        start_cli("topic", "pub", "-r", "50", "/odd", "my_pkg/Odd_Name", "x: 3", env=env),
    ]
    rec: Proc | None = None
    try:
        rec = start_cli(
            "bag", "record", "--to", "ros2", "-O", "run", "/h", "/latched", "/odd", "-F", "json",
            env=env, cwd=tmp_path,
        )  # fmt: skip
        wait_for(lambda: subscribed(rostools_master, "/odd", "/rostools_record"), 15, "subscribe")
        inner = tmp_path / "run.active" / "run_0.mcap"
        wait_for(lambda: recorded(inner, "/h") >= 20, 30, "20 on /h on disk", 0.2)
        # rewritten with each flush: a recorder killed now leaves a folder that says what it holds
        wait_for(lambda: (inner.parent / "metadata.yaml").exists(), 10, "metadata.yaml", 0.2)
        rec.expect(r"Odd_Name", stderr=True)  # said as soon as it first sends
        rec.signal(signal.SIGTERM)
        out, err = rec.output()
        assert rec.popen.returncode == 6, err
    finally:
        for proc in [*pubs, *([rec] if rec else [])]:
            proc.stop()
    said = [line for line in err.splitlines() if "/odd" in line and "Subscribing" not in line]
    assert len(said) == 2, err  # when it first sent, and in the exit's line
    assert "my_pkg/Odd_Name" in said[0] and "/odd is left out of the recording" in said[0]
    assert said[1] == "rostools: 1 topic not convertible to ROS 2: /odd"
    summary = json.loads(out)
    assert summary["files"] == ["run"] and list(summary["left_out"]) == ["/odd"]
    assert not (tmp_path / "run.active").exists()
    got = decoded(tmp_path / "run")
    assert set(got) == {"/h", "/latched"}
    assert len(got["/h"]) == summary["topics"]["/h"]["received"] >= 20  # none lost on SIGTERM
    for msg in got["/h"]:
        assert (msg.header.frame_id, msg.header.stamp.sec, msg.point.x) == ("f", 0, 1.5)
        assert not hasattr(msg.header, "seq")
    assert [m.data for m in got["/latched"]] == ["kept"]
    assert durability(tmp_path / "run") == {"/h": "volatile", "/latched": "transient_local"}


@pytest.mark.parametrize(
    "args, says",
    [
        (["--to", "ros3"], "unknown --to 'ros3'"),
        (["--to", "ros2", "--distro", "hoary"], "unknown ROS 2 distro 'hoary'"),
        (["--distro", "jazzy"], "--distro and --types are for --to ros2"),
        (["--to", "ros2", "--types", "types.yaml"], "types.yaml is not YAML"),
        (["--to", "ros2", "--split", "--size", "1"], "--split is for .bag and MCAP"),
        (["--to", "ros2", "--bz2"], "--to ros2 writes MCAP"),
        (["--to", "ros2", "-O", "taken"], "taken exists"),
        (["--to", "ros2", "-O", "run.mcap"], "name it without .mcap"),
    ],
)
def test_record_to_ros2_usage_errors(
    cli_env: dict[str, str], tmp_path: Path, args: list[str], says: str
) -> None:
    (tmp_path / "taken").mkdir()
    (tmp_path / "types.yaml").write_text("renames: [unclosed\n")
    done = run_cli("bag", "record", "/x", *args, env=cli_env, cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    assert says in done.stderr and len(done.stderr.strip().splitlines()) <= 2
    assert "Traceback" not in done.stderr


def test_record_to_ros2_takes_a_types_file_and_a_count(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    """A rename in ``--types`` gives the type ROS 2 could not name a name; ``-l`` stops it."""
    (tmp_path / "types" / "my_pkg" / "msg").mkdir(parents=True)
    (tmp_path / "types" / "my_pkg" / "msg" / "Odd_Name.msg").write_text("int32 x\n")
    (tmp_path / "rules.yaml").write_text("renames:\n  my_pkg/Odd_Name: my_pkg/msg/OddName\n")
    env = dict(cli_env, ROSTOOLS_MSG_PATH=str(tmp_path / "types"))
    pub = start_cli("topic", "pub", "-r", "50", "/odd", "my_pkg/Odd_Name", "x: 3", env=env)
    try:
        done = run_cli(
            "bag", "record", "--to", "ros2", "--types", "rules.yaml", "-O", "odd", "-l", "3",
            "/odd", env=env, cwd=tmp_path,
        )  # fmt: skip
    finally:
        pub.stop()
    assert done.returncode == 0, done.stderr
    from rosbags.rosbag2 import Reader

    with Reader(tmp_path / "odd") as reader:
        assert [c.msgtype for c in reader.connections] == ["my_pkg/msg/OddName"]
        raws = [raw for _, _, raw in reader.messages()]
    assert raws == [b"\x00\x01\x00\x00\x03\x00\x00\x00"] * 3  # CDR: header, then int32 3
