"""A rospy TransformBroadcaster of a moving frame: odom -> base (or the frames given).

Its stamps lie on a grid of 1/64 s, which float seconds hold exactly: tf2_py, which reads
times as float seconds, then stores the very stamps sent, and its answers can be compared
to the ns. The pose is a function of the stamp: x = sin(t), y = cos(t), yaw = 0.7 t.

Run with the system python: tf_broadcaster.py [parent] [child] [silent]
(``silent``: it advertises /tf and never sends.)
"""

import math
import sys

import rospy
import tf2_ros
from geometry_msgs.msg import TransformStamped

GRID = 15_625_000  # ns: 1/64 s

parent = sys.argv[1] if len(sys.argv) > 1 else "odom"
child = sys.argv[2] if len(sys.argv) > 2 else "base"
rospy.init_node("silent_broadcaster" if sys.argv[3:] == ["silent"] else "moving_broadcaster")
broadcaster = tf2_ros.TransformBroadcaster()
rate = rospy.Rate(64)
last = 0
if sys.argv[3:] == ["silent"]:
    rospy.spin()
while not rospy.is_shutdown():
    ns = rospy.Time.now().to_nsec() // GRID * GRID
    if ns > last:
        last = ns
        t = ns / 1e9
        m = TransformStamped()
        m.header.stamp = rospy.Time(ns // 1_000_000_000, ns % 1_000_000_000)
        m.header.frame_id, m.child_frame_id = parent, child
        m.transform.translation.x, m.transform.translation.y = math.sin(t), math.cos(t)
        m.transform.rotation.z, m.transform.rotation.w = math.sin(0.35 * t), math.cos(0.35 * t)
        broadcaster.sendTransform(m)
    rate.sleep()
