"""A rospy listener: prints the data field of each message, one per line.

Run with the system python: listener.py [topic] [type, default std_msgs/String]
"""

import sys

import roslib.message
import rospy

topic = sys.argv[1] if len(sys.argv) > 1 else "/chatter"
type_name = sys.argv[2] if len(sys.argv) > 2 else "std_msgs/String"
cls = roslib.message.get_message_class(type_name)


def callback(msg):
    value = msg.data if hasattr(msg, "data") else msg.msg
    print(f"got {value}", flush=True)


rospy.init_node("listener", anonymous=True)
rospy.Subscriber(topic, cls, callback)
print("ready", flush=True)
rospy.spin()
