"""tf2's own ``BufferCore`` fed, then its ``allFramesAsYAML``: the truth for ``tf frames``.

``tf2_buffer.py`` reads transforms as JSON lines on stdin (parent, child, stamp_ns, t, q, who,
static); ``tf2_buffer.py BAG`` reads ``/tf`` and ``/tf_static`` from a bag with rosbag, each
message's broadcaster its connection's callerid, as a TransformListener would have them.
Either way it prints the buffer's YAML.
"""

import json
import sys

import rospy
import tf2_py
from geometry_msgs.msg import TransformStamped

buffer = tf2_py.BufferCore(rospy.Duration(10))


def feed(t, who, static):
    if static:
        buffer.set_transform_static(t, who)
    else:
        buffer.set_transform(t, who)


if len(sys.argv) > 1:
    import rosbag

    with rosbag.Bag(sys.argv[1]) as bag:
        topics = ["/tf", "/tf_static", "tf", "tf_static"]
        for topic, msg, _, header in bag.read_messages(
            topics=topics, return_connection_header=True
        ):
            static = topic.lstrip("/") == "tf_static"
            who = header.get("callerid", b"")  # rosbag hands the header over as bytes
            who = who.decode() if isinstance(who, bytes) else who
            for t in msg.transforms:
                feed(t, who, static)
else:
    for line in sys.stdin:
        d = json.loads(line)
        t = TransformStamped()
        t.header.frame_id, t.child_frame_id = d["parent"], d["child"]
        t.header.stamp = rospy.Time(d["stamp_ns"] // 10**9, d["stamp_ns"] % 10**9)
        t.transform.translation.x, t.transform.translation.y, t.transform.translation.z = d["t"]
        r = t.transform.rotation
        r.x, r.y, r.z, r.w = d["q"]
        feed(t, d["who"], d["static"])
print(buffer.all_frames_as_yaml())
