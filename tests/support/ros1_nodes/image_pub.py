"""Publishes sensor_msgs/Image of about 1 MB on /image at 2 Hz; prints the md5 of each data.

Run with the system python: image_pub.py [latch 0|1]
"""

import hashlib
import sys

import rospy
from sensor_msgs.msg import Image

latch = len(sys.argv) > 1 and sys.argv[1] == "1"
rospy.init_node("image_pub")
pub = rospy.Publisher("/image", Image, queue_size=10, latch=latch)
n = 0
rate = rospy.Rate(2)
while not rospy.is_shutdown():
    data = bytes((i * 7 + n) % 251 for i in range(1_048_576))
    pub.publish(Image(height=512, width=683, encoding="rgb8", step=2048, data=data))
    print(f"sent {hashlib.md5(data).hexdigest()}", flush=True)
    n += 1
    rate.sleep()
