"""Calls per second of a persistent rospy ServiceProxy: std_srvs/Trigger on /trigger.

Usage: rospy_service_calls.py SECONDS   (system python; prints {"calls", "seconds"} as JSON)
"""

import json
import sys
import time

import rospy
from std_srvs.srv import Trigger

seconds = float(sys.argv[1])
rospy.wait_for_service("/trigger", timeout=20)
proxy = rospy.ServiceProxy("/trigger", Trigger, persistent=True)
proxy()
calls, start = 0, time.monotonic()
while time.monotonic() - start < seconds:
    proxy()
    calls += 1
print(json.dumps({"calls": calls, "seconds": time.monotonic() - start}), flush=True)
