"""A rospy node that logs at every level, a round every 0.1 s: "LEVEL N" (debug 0, info 0, ...).

Run with the system python: log_levels.py [name=log_levels]. Prints "ready" once it logs.
"""

import sys

import rospy

name = sys.argv[1] if len(sys.argv) > 1 else "log_levels"
rospy.init_node(name)
rate = rospy.Rate(10)
n = 0
print("ready", flush=True)
while not rospy.is_shutdown():
    rospy.logdebug("debug %d", n)
    rospy.loginfo("info %d", n)
    rospy.logwarn("warn %d", n)
    rospy.logerr("error %d", n)
    rospy.logfatal("fatal %d", n)
    n += 1
    rate.sleep()
