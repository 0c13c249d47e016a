"""A real tf2 listener: ``tf_lookup.py PARENT CHILD [PARENT CHILD...]``.

``tf2_ros.Buffer`` with a ``TransformListener``; once every pair looks up (at time 0, the
latest), one JSON line per pair (translation, rotation, the values as received), then exit.
"""

import json
import sys

import rospy
import tf2_ros

rospy.init_node("tf_lookup", anonymous=True)
pairs = list(zip(sys.argv[1::2], sys.argv[2::2], strict=True))
buffer = tf2_ros.Buffer()
listener = tf2_ros.TransformListener(buffer)
found = {}
while not rospy.is_shutdown() and len(found) < len(pairs):
    for parent, child in pairs:
        try:
            t = buffer.lookup_transform(parent, child, rospy.Time(0))
        except tf2_ros.TransformException:
            continue
        v, q = t.transform.translation, t.transform.rotation
        found[(parent, child)] = {
            "parent": parent,
            "child": child,
            "t": [v.x, v.y, v.z],
            "q": [q.x, q.y, q.z, q.w],
        }
    rospy.sleep(0.05)
for pair in pairs:
    print(json.dumps(found[pair]), flush=True)
