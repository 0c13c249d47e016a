"""ROS 2 (CDR) MCAP into a ROS 1 .bag (issue 15): common types map onto their Noetic twins."""

from __future__ import annotations

from pathlib import Path

from tests.support.env import (
    CORPUS,
    needs_corpus,
    needs_ros1,
    run_cli,
    run_system_python,
)


def _ros2_mcap(path: Path, count: int) -> None:
    """PoseStamped (a header: stamp and frame_id, no seq) written as ros2 bag would."""
    from mcap.writer import Writer
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    name = "geometry_msgs/msg/PoseStamped"
    text, _ = ts.generate_msgdef(name, ros_version=2)
    T = ts.types  # noqa: N806
    with path.open("wb") as f:
        writer = Writer(f)
        writer.start("ros2", "test")
        schema = writer.register_schema(name, "ros2msg", text.encode())
        channel = writer.register_channel("/pose", "cdr", schema)
        for i in range(count):
            stamp = T["builtin_interfaces/msg/Time"](sec=100 + i, nanosec=7)
            header = T["std_msgs/msg/Header"](stamp=stamp, frame_id="map")
            point = T["geometry_msgs/msg/Point"](x=float(i), y=-1.5, z=0.25)
            orientation = T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0)
            pose = T["geometry_msgs/msg/Pose"](position=point, orientation=orientation)
            msg = T[name](header=header, pose=pose)
            t = (100 + i) * 10**9
            writer.add_message(channel, t, bytes(ts.serialize_cdr(msg, name)), t)
        writer.finish()


@needs_ros1
def test_convert_ros2_posestamped_to_a_bag_rosbag_reads(tmp_path: Path) -> None:
    _ros2_mcap(tmp_path / "in.mcap", 3)
    out = tmp_path / "out.bag"
    done = run_cli("bag", "convert", str(tmp_path / "in.mcap"), str(out))
    assert done.returncode == 0, done.stderr
    script = (
        "import rosbag, sys\n"
        "for topic, m, t in rosbag.Bag(sys.argv[1]).read_messages():\n"
        "    print(topic, m._type, m.header.stamp.secs, m.header.stamp.nsecs, m.header.frame_id,"
        " m.pose.position.x, m.pose.orientation.w, t.to_nsec())\n"
    )
    stdout = run_system_python(script, str(out))
    assert stdout.splitlines() == [
        f"/pose geometry_msgs/PoseStamped {100 + i} 7 map {float(i)} 1.0 {(100 + i) * 10**9}"
        for i in range(3)
    ]


@needs_corpus
def test_types_without_a_ros1_twin_are_refused_by_name(tmp_path: Path) -> None:
    talker = CORPUS / "mcap" / "rosbag2" / "rosbag2_py" / "talker" / "talker.mcap"
    out = tmp_path / "t.bag"
    refused = run_cli("bag", "convert", str(talker), str(out))
    assert refused.returncode == 1 and not out.exists()
    assert "the ROS 2 type rcl_interfaces/msg/Log has no ROS 1 twin" in refused.stderr
    kept = run_cli("bag", "filter", str(talker), str(out), "-t", "/topic")
    assert kept.returncode == 0, kept.stderr
    cat = run_cli("bag", "cat", str(out), "-n", "1")
    assert '"type":"std_msgs/String"' in cat.stdout and "Hello, world! 0" in cat.stdout


@needs_corpus
def test_ros2_mcap_merges_splits_and_filters_into_mcap_as_it_is(tmp_path: Path) -> None:
    from mcap.reader import make_reader

    src = CORPUS / "mcap" / "rosbag2" / "rosbag2_tests" / "cdr_test" / "cdr_test_0.mcap"
    one = tmp_path / "one.mcap"
    assert run_cli("bag", "filter", str(src), str(one), "-t", "/test_topic").returncode == 0
    both = tmp_path / "both.mcap"
    merged = run_cli("bag", "merge", str(both), str(src), str(one), "--rename", "/x:=/y")
    assert merged.returncode == 0, merged.stderr
    split = run_cli("bag", "split", str(both), "--count", "5", "-o", str(tmp_path / "p.mcap"))
    assert split.returncode == 0, split.stderr
    for verb in ("convert", "recover"):
        done = run_cli("bag", verb, str(src), str(tmp_path / f"{verb}.mcap"))
        assert done.returncode == 0, done.stderr
    with src.open("rb") as f:
        original = {c.topic: c for c in make_reader(f).get_summary().channels.values()}
    parts = [tmp_path / f"{name}.mcap" for name in ("p_0", "p_1", "convert", "recover")]
    for path in (one, both, *parts):
        with path.open("rb") as f:
            reader = make_reader(f)
            assert reader.get_header().profile == "ros2"
            summary = reader.get_summary()
            for c in summary.channels.values():  # bytes, encodings and metadata as they were
                assert c.message_encoding == "cdr" and c.metadata == original[c.topic].metadata
                assert summary.schemas[c.schema_id].encoding == "ros2msg"
    lines = run_cli("bag", "cat", str(both)).stdout.splitlines()
    again = run_cli("bag", "cat", str(src), str(one)).stdout.splitlines()
    assert len(lines) == 10 and [_msg(x) for x in lines] == [_msg(x) for x in again]
    # A .bag cannot hold CDR bytes: merge refuses before writing, and names why.
    refused = run_cli("bag", "merge", str(tmp_path / "m.bag"), str(src))
    assert refused.returncode == 1 and "ROS 2 CDR" in refused.stderr
    assert not (tmp_path / "m.bag").exists()


def _msg(line: str) -> object:
    import json

    data = json.loads(line)
    return data["topic"], data["log_time"], data["msg"]
