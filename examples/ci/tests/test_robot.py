"""The robot's behaviour, each test on a master of its own (the rostools pytest plugin)."""

import rostools
from rostools.testing import assert_message, assert_topic_rate


def test_heartbeat_keeps_its_rate(start_node):
    """~rate is the rate it beats at."""
    start_node("heartbeat.py", "_rate:=20")
    assert_topic_rate("/heartbeat", hz=20, tolerance=0.2, within=5)


def test_speed_is_limited(start_node):
    """A command over ~max_speed leaves clamped; the rest of it passes unchanged."""
    rostools.set_param("/speed_limiter/max_speed", 0.5)
    start_node("speed_limiter.py")
    rostools.publish(
        "/cmd_vel", {"linear": {"x": 2.0}, "angular": {"z": 0.3}}, "geometry_msgs/Twist"
    )
    safe = assert_message("/cmd_vel_safe", timeout=5)
    assert (safe.linear.x, safe.angular.z) == (0.5, 0.3)


def test_heartbeat_can_be_switched_off(start_node, ros_record):
    """~enable false stops the beats; what was recorded before is all beats."""
    start_node("heartbeat.py", "_rate:=50")
    recording = ros_record("/heartbeat")
    assert_message("/heartbeat", {"data": "alive"}, timeout=5)
    answer = rostools.call_service("/heartbeat/enable", data=False)
    assert (answer.success, answer.message) == (True, "off")
    bag = recording.stop()
    beats = [m for m in rostools.read_bag(bag) if m.topic == "/heartbeat"]
    assert beats and all(m.message.data == "alive" for m in beats)
    # off means off: nothing comes for half a second
    with rostools.subscribe("/heartbeat") as sub:
        try:
            sub.get(timeout=0.5)
        except rostools.TimeoutExpired:
            pass
        else:
            raise AssertionError("the heartbeat still beats after ~enable false")
