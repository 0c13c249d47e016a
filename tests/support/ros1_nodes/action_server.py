"""A rospy actionlib SimpleActionServer (actionlib/TestAction). Run with the system python.

action_server.py [NAME]: serves NAME (default fib).

The goal's number says what happens, as in rt_nodes/rt_actions.py: n > 0 publishes feedback
1..n every 50 ms and succeeds with result n * 10; n < 0 aborts; 666 kills the process after
the first feedback; a cancel preempts the goal with the feedback count so far.
"""

import os
import sys

import actionlib
import rospy
from actionlib.msg import TestAction, TestFeedback, TestResult


def execute(goal):
    n = goal.goal
    if n < 0:
        server.set_aborted(TestResult(0), f"negative goal {n}")
        return
    rate = rospy.Rate(20)
    for i in range(1, n + 1):
        if server.is_preempt_requested():
            server.set_preempted(TestResult(i - 1), f"preempted at {i - 1}")
            return
        server.publish_feedback(TestFeedback(i))
        if n == 666:
            rospy.sleep(0.2)  # the feedback leaves first
            os._exit(3)
        rate.sleep()
    server.set_succeeded(TestResult(n * 10), "done")


NAME = sys.argv[1] if len(sys.argv) > 1 else "fib"
rospy.init_node(NAME.strip("/").replace("/", "_") + "_server")
server = actionlib.SimpleActionServer(NAME, TestAction, execute_cb=execute, auto_start=False)
server.start()
print("ready", flush=True)
rospy.spin()
