#!/usr/bin/env python3
"""Publishes "alive" on /heartbeat at ~rate Hz while on; ~enable (std_srvs/SetBool) switches it."""

import rospy
from std_msgs.msg import String
from std_srvs.srv import SetBool, SetBoolResponse


def main():
    """Run the node until it is shut down."""
    rospy.init_node("heartbeat")
    rate = rospy.Rate(float(rospy.get_param("~rate", 10.0)))
    pub = rospy.Publisher("heartbeat", String, queue_size=10)
    state = {"enabled": True}

    def enable(request):
        """~enable: on with true, off with false."""
        state["enabled"] = request.data
        return SetBoolResponse(success=True, message="on" if request.data else "off")

    rospy.Service("~enable", SetBool, enable)
    while not rospy.is_shutdown():
        if state["enabled"]:
            pub.publish(String(data="alive"))
        rate.sleep()


if __name__ == "__main__":
    main()
