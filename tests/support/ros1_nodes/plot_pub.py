"""A rospy publisher for the plot tests: /odom and /scan, each value a function of its stamp.

Message k (from 0): header.stamp = 1000 + k seconds on both topics; /odom's
pose.pose.position.x = k / 2; /scan's ranges = [k, k + 1, k + 2, k + 3].
Run with the system python: plot_pub.py [rate_hz]
"""

import sys

import rospy
from nav_msgs.msg import Odometry
from sensor_msgs.msg import LaserScan

rate_hz = float(sys.argv[1]) if len(sys.argv) > 1 else 50.0
rospy.init_node("plot_pub")
odom = rospy.Publisher("/odom", Odometry, queue_size=100)
scan = rospy.Publisher("/scan", LaserScan, queue_size=100)
rate = rospy.Rate(rate_hz)
k = 0
while not rospy.is_shutdown():
    stamp = rospy.Time(1000 + k)
    o = Odometry()
    o.header.stamp = stamp
    o.header.frame_id = "odom"
    o.pose.pose.position.x = k / 2
    odom.publish(o)
    s = LaserScan()
    s.header.stamp = stamp
    s.header.frame_id = "laser"
    s.ranges = [float(k + i) for i in range(4)]
    scan.publish(s)
    k += 1
    rate.sleep()
