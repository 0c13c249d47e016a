"""``bag record --to ros2`` of a real rospy publisher, on ``rostools core`` and a real roscore.

rospy (``ros2_mix.py``) sends headers with ``seq``, times, a nested array and a latched topic;
rosbags' rosbag2 reader reads the folder, and every message equals what rospy sent, less
``seq``, with none missing between the first and the last.
"""

from __future__ import annotations

import signal
from pathlib import Path
from typing import Any

import pytest

from tests.conftest import MasterInfo
from tests.integration.test_record_ros2 import decoded, durability
from tests.support.bagdata import recorded
from tests.support.env import needs_ros1
from tests.support.procs import start_cli, start_ros1_node, wait_for

pytestmark = [pytest.mark.interop, needs_ros1]


def imu_index(msg: Any) -> int:
    """n of ros2_mix.py's n-th /imu message, checked field by field against it."""
    n = msg.header.stamp.sec - 1000
    assert (msg.header.stamp.nanosec, msg.header.frame_id) == (7 * n, f"imu{n}")
    assert (msg.orientation.w, msg.angular_velocity.z) == (float(n), -0.5 * n)
    assert list(msg.linear_acceleration_covariance) == [float(n + k) for k in range(9)]
    assert list(msg.orientation_covariance) == [0.0] * 9
    assert not hasattr(msg.header, "seq")
    return n


def poly_index(msg: Any) -> int:
    """n of ros2_mix.py's n-th /poly message, checked against it."""
    n = msg.header.stamp.sec - 2000
    assert (msg.header.stamp.nanosec, msg.header.frame_id) == (0, "map")
    points = [(p.x, p.y, p.z) for p in msg.polygon.points]
    assert points == [(float(k), float(n), 0.25) for k in range(n % 4)]
    return n


def test_record_to_ros2_of_a_rospy_publisher(any_master: MasterInfo, tmp_path: Path) -> None:
    rec = start_cli(
        "bag", "record", "--to", "ros2", "-O", "mix", "/imu", "/poly", "/latched",
        env=any_master.cli_env, cwd=tmp_path,
    )  # fmt: skip
    pub = start_ros1_node("ros2_mix.py", ["50"], any_master.ros_env)
    try:
        inner = tmp_path / "mix.active" / "mix_0.mcap"
        for topic, count in (("/imu", 20), ("/poly", 20), ("/latched", 1)):
            wait_for(lambda t=topic, n=count: recorded(inner, t) >= n, 30, topic, 0.2)
        rec.signal(signal.SIGINT)
        assert rec.popen.wait(20) == 0, rec.output()[1]
    finally:
        pub.stop()
        rec.stop()
    got = decoded(tmp_path / "mix")
    for topic, index in (("/imu", imu_index), ("/poly", poly_index)):
        ns = [index(m) for m in got[topic]]
        assert len(ns) >= 20 and ns == list(range(ns[0], ns[0] + len(ns))), topic
    assert [m.data for m in got["/latched"]] == ["kept"]
    assert durability(tmp_path / "mix") == {
        "/imu": "volatile", "/poly": "volatile", "/latched": "transient_local"
    }  # fmt: skip
