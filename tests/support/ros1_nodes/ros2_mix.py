"""A rospy node of the types a ROS 2 recording changes: headers, time, nested arrays, latching.

Message n on /imu (sensor_msgs/Imu) and /poly (geometry_msgs/PolygonStamped) is a function
of n (see ``expected`` in tests/interop/test_record_ros2_interop.py); /latched
(std_msgs/String, latched) says "kept" once. rospy fills each header's seq.

Run with the system python: ros2_mix.py [rate_hz]
"""

import sys

import rospy
from geometry_msgs.msg import Point32, PolygonStamped
from sensor_msgs.msg import Imu
from std_msgs.msg import String

rate_hz = float(sys.argv[1]) if len(sys.argv) > 1 else 50.0
rospy.init_node("ros2_mix")
latched = rospy.Publisher("/latched", String, queue_size=1, latch=True)
latched.publish(String(data="kept"))
imu = rospy.Publisher("/imu", Imu, queue_size=100)
poly = rospy.Publisher("/poly", PolygonStamped, queue_size=100)
rate = rospy.Rate(rate_hz)
n = 0
while not rospy.is_shutdown():
    m = Imu()
    m.header.stamp = rospy.Time(1000 + n, 7 * n)
    m.header.frame_id = f"imu{n}"
    m.orientation.w = float(n)
    m.angular_velocity.z = -0.5 * n
    m.linear_acceleration_covariance = [float(n + k) for k in range(9)]
    imu.publish(m)
    p = PolygonStamped()
    p.header.stamp = rospy.Time(2000 + n, 0)
    p.header.frame_id = "map"
    p.polygon.points = [Point32(x=float(k), y=float(n), z=0.25) for k in range(n % 4)]
    poly.publish(p)
    n += 1
    rate.sleep()
