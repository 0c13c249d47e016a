#!/usr/bin/env python3
"""Passes /cmd_vel on to /cmd_vel_safe with the linear speed clamped to ~max_speed (m/s)."""

import rospy
from geometry_msgs.msg import Twist


def main():
    """Run the node until it is shut down."""
    rospy.init_node("speed_limiter")
    limit = float(rospy.get_param("~max_speed", 1.0))
    out = rospy.Publisher("cmd_vel_safe", Twist, queue_size=10, latch=True)

    def on_command(cmd):
        """A command in, the clamped command out."""
        cmd.linear.x = max(-limit, min(limit, cmd.linear.x))
        out.publish(cmd)

    rospy.Subscriber("cmd_vel", Twist, on_command)
    rospy.spin()


if __name__ == "__main__":
    main()
