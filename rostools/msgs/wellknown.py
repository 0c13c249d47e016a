"""The few ROS types rostools speaks itself, with their md5sums: one home for each.

``bag play`` publishes ``/clock`` and serves ``~pause_playback``; ``bag record -p`` and
``bag snapshot`` publish file names as strings; ``bag snapshot`` serves std_srvs/Trigger and
rosbag_snapshot's ``TriggerSnapshot``, which ``bag trigger`` calls. Each md5sum is checked
against its definition in ``tests/unit/msgs/test_wellknown.py``.
"""

from __future__ import annotations

from rostools.msgs.topictype import ServiceType, TopicType

#: std_msgs/String: ``string data``.
STRING = TopicType("std_msgs/String", "992ce8a1687cec8c8bd883ec73ca41d1", "string data\n")
#: rosgraph_msgs/Clock, as roscpp and rospy announce it.
CLOCK = TopicType(
    "rosgraph_msgs/Clock",
    "a9c97c1d230cfc112e270351a944ee47",
    "# roslib/Clock is used for publishing simulated time in ROS. \n"
    "# This message simply communicates the current time.\n"
    "# For more information, see http://www.ros.org/wiki/Clock\n"
    "time clock\n",
)
#: std_srvs/Trigger: no request; ``bool success, string message``.
TRIGGER = ServiceType("std_srvs/Trigger", "937c9679a518e3a18d831e57125ea522")
#: std_srvs/SetBool: ``bool data`` --- ``bool success, string message``.
SET_BOOL = ServiceType("std_srvs/SetBool", "09fb03525b03e7ea1fd3992bafd87e16")
#: rosbag_snapshot_msgs/TriggerSnapshot (``bag/live/snapshot_srv.py`` reads and writes it).
TRIGGER_SNAPSHOT = ServiceType(
    "rosbag_snapshot_msgs/TriggerSnapshot", "d5f2b150730729bd0435527e829e65e2"
)
#: Its definition, for the md5 check in the tests.
TRIGGER_SNAPSHOT_TEXT = (
    "string filename\nstring[] topics\ntime start_time\ntime stop_time\n---\n"
    "string NO_DATA_MESSAGE=no messages buffered on selected topics\n"
    "bool success\nstring message\n"
)
