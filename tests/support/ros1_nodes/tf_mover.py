"""A rospy tf2 broadcaster of moving frames: ``tf_mover.py RATE PARENT CHILD [PARENT CHILD...]``.

Each period it sends one /tf message holding every pair, rotating about z with time, stamped
now, through ``tf2_ros.TransformBroadcaster``; it prints "broadcasting" once the first is out.
"""

import math
import sys

import rospy
import tf2_ros
from geometry_msgs.msg import TransformStamped

rospy.init_node("tf_mover")
rate_hz = float(sys.argv[1])
pairs = list(zip(sys.argv[2::2], sys.argv[3::2], strict=True))
broadcaster = tf2_ros.TransformBroadcaster()
rate = rospy.Rate(rate_hz)
said = False
while not rospy.is_shutdown():
    now = rospy.Time.now()
    angle = now.to_sec() % (2 * math.pi)
    out = []
    for i, (parent, child) in enumerate(pairs):
        t = TransformStamped()
        t.header.stamp = now
        t.header.frame_id = parent
        t.child_frame_id = child
        t.transform.translation.x = 1.0 + i
        t.transform.rotation.z = math.sin(angle / 2)
        t.transform.rotation.w = math.cos(angle / 2)
        out.append(t)
    broadcaster.sendTransform(out)
    if not said:
        print("broadcasting", flush=True)
        said = True
    try:
        rate.sleep()
    except rospy.ROSInterruptException:
        break
