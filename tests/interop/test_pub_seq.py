"""``header.seq`` of a latched ``topic pub``, as rostopic pub (rospy) numbers it.

rospy counts a publish only when it reaches a subscriber, and sends the latched message to
each subscriber that connects later as a new publish: the first gets seq 1, the next 2. Ours
sent seq 0, the number in the message as it was written.
"""

from __future__ import annotations

import json

import pytest

from tests.support.env import needs_ros1, run_cli
from tests.support.procs import Proc, start_cli, wait_for

pytestmark = [pytest.mark.interop, needs_ros1]


def _seq(env: dict[str, str], topic: str) -> int:
    echo = run_cli("topic", "echo", topic, "-n", "1", "--timeout", "20", "-F", "json", env=env)
    assert echo.returncode == 0, echo.stderr
    return int(json.loads(echo.stdout)["header"]["seq"])


def test_a_latched_pub_numbers_as_rostopic(rostools_master: str, cli_env: dict[str, str]) -> None:
    ros_env = dict(cli_env, ROS_HOME=cli_env["HOME"])
    message = "{header: {frame_id: map}}"
    theirs = Proc(["rostopic", "pub", "/theirs", "geometry_msgs/PointStamped", message],
                  env=ros_env)  # fmt: skip
    ours = start_cli("topic", "pub", "/ours", "geometry_msgs/PointStamped", message, env=cli_env)
    try:
        topics = lambda: run_cli("topic", "list", env=cli_env).stdout.split()  # noqa: E731
        wait_for(lambda: {"/ours", "/theirs"} <= set(topics()), 30, "both publishers")
        got = [(_seq(cli_env, "/theirs"), _seq(cli_env, "/ours")) for _ in range(3)]
    finally:
        theirs.stop()
        ours.stop()
    assert got == [(1, 1), (2, 2), (3, 3)]
