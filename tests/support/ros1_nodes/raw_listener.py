"""A rospy listener of any type (rospy.AnyMsg): one line per message, as it arrives.

Run with the system python: raw_listener.py TOPIC

Prints "ready" once subscribed, then for each message: "got SECONDS LENGTH MD5 HEAD", where
SECONDS is time.monotonic() when rospy handed it over, LENGTH and MD5 those of its
serialized bytes, and HEAD its first 64 bytes in hex. The type, md5sum and definition the
publisher sent are printed once, on a line "type TYPE MD5SUM DEFINITION_LENGTH".
"""

import hashlib
import sys
import time

import rospy

topic = sys.argv[1]
typed = False


def callback(msg):
    global typed
    arrived = time.monotonic()
    data = bytes(msg._buff)
    if not typed:
        header = msg._connection_header
        print(
            "type",
            header["type"],
            header["md5sum"],
            len(header.get("message_definition", "")),
            flush=True,
        )
        typed = True
    digest = hashlib.md5(data).hexdigest()
    print(f"got {arrived:.6f} {len(data)} {digest} {data[:64].hex()}", flush=True)


rospy.init_node("raw_listener", anonymous=True)
rospy.Subscriber(topic, rospy.AnyMsg, callback)
print("ready", flush=True)
rospy.spin()
