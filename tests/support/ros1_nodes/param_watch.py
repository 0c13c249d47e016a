"""Prints a parameter each time rospy.get_param_cached sees it change (paramUpdate).

Run with the system python: param_watch.py KEY
"""

import sys

import rospy

key = sys.argv[1]
rospy.init_node("param_watch")
last = object()
print("ready", flush=True)
while not rospy.is_shutdown():
    try:
        value = rospy.get_param_cached(key)
    except KeyError:
        value = None
    if value != last:
        print(f"value {value!r}", flush=True)
        last = value
    rospy.sleep(0.05)
