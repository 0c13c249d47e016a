"""A rospy talker: std_msgs/String "hello N" on a topic (default /chatter), logged to /rosout.

Run with the system python: talker.py [topic] [rate_hz] [latch 0|1] [count]
"""

import sys

import rospy
from std_msgs.msg import String

topic = sys.argv[1] if len(sys.argv) > 1 else "/chatter"
rate_hz = float(sys.argv[2]) if len(sys.argv) > 2 else 20.0
latch = len(sys.argv) > 3 and sys.argv[3] == "1"
count = int(sys.argv[4]) if len(sys.argv) > 4 else -1
rospy.init_node("talker")
pub = rospy.Publisher(topic, String, queue_size=100, latch=latch)
rate = rospy.Rate(rate_hz)
n = 0
while not rospy.is_shutdown() and n != count:
    pub.publish(String(data=f"hello {n}"))
    rospy.loginfo("said hello %d", n)
    n += 1
    rate.sleep()
rospy.spin()
