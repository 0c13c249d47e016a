"""rospy's publisher and subscriber, the reference for throughput (system python).

Usage: rospy_pubsub.py pub TOPIC SIZE SECONDS | rospy_pubsub.py sub TOPIC SECONDS
"""

import json
import sys
import time

import rospy
from rospy.msg import AnyMsg
from sensor_msgs.msg import Image
from std_msgs.msg import String

role, topic = sys.argv[1], sys.argv[2]
if role == "pub":
    size, seconds = int(sys.argv[3]), float(sys.argv[4])
    rospy.init_node("rospy_pub", anonymous=True)
    if size >= 100_000:
        msg = Image(height=1, width=size, encoding="mono8", step=size, data=bytes(size))
        pub = rospy.Publisher(topic, Image, queue_size=10)
    else:
        msg = String(data="x" * max(size - 4, 0))
        pub = rospy.Publisher(topic, String, queue_size=10000)
    while pub.get_num_connections() == 0 and not rospy.is_shutdown():
        time.sleep(0.01)
    end = time.monotonic() + seconds
    while time.monotonic() < end and not rospy.is_shutdown():
        pub.publish(msg)
else:
    seconds = float(sys.argv[3])
    rospy.init_node("rospy_sub", anonymous=True)
    state = {"n": 0, "bytes": 0, "start": 0.0}

    def callback(m):
        if state["start"] == 0.0:
            state["start"] = time.monotonic()
        state["n"] += 1
        state["bytes"] += len(m._buff)

    rospy.Subscriber(topic, AnyMsg, callback, queue_size=100000)
    while state["start"] == 0.0 and not rospy.is_shutdown():
        time.sleep(0.01)
    time.sleep(seconds)
    elapsed = time.monotonic() - state["start"]
    print(
        json.dumps({"messages": state["n"], "bytes": state["bytes"], "seconds": elapsed}),
        flush=True,
    )
    rospy.signal_shutdown("done")
