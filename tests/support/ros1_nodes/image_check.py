"""Subscribes to sensor_msgs/Image on /image and prints the md5 and size of each data field.

Run with the system python: image_check.py
"""

import hashlib

import rospy
from sensor_msgs.msg import Image


def callback(msg):
    print(f"got {hashlib.md5(msg.data).hexdigest()} {len(msg.data)} {msg.encoding}", flush=True)


rospy.init_node("image_check", anonymous=True)
rospy.Subscriber("/image", Image, callback)
print("ready", flush=True)
rospy.spin()
