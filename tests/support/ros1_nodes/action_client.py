"""A rospy actionlib SimpleActionClient (actionlib/TestAction). Run with the system python.

action_client.py NAME N...: for each N, send the goal to NAME, count its feedback and print
``result N <state name> <result> <feedback count> <text>``; a goal 1000 is canceled after
its third feedback.
"""

import sys

import actionlib
import rospy
from actionlib.msg import TestAction, TestGoal
from actionlib_msgs.msg import GoalStatus

NAMES = {getattr(GoalStatus, n): n for n in dir(GoalStatus) if n.isupper()}

rospy.init_node("fib_client")
client = actionlib.SimpleActionClient(sys.argv[1], TestAction)
if not client.wait_for_server(rospy.Duration(20)):
    print("no server", flush=True)
    sys.exit(1)
print("ready", flush=True)
for arg in sys.argv[2:]:
    n = int(arg)
    seen = []

    def feedback(fb, n=n, seen=seen):
        seen.append(fb.feedback)
        if n == 1000 and len(seen) == 3:
            client.cancel_goal()

    client.send_goal(TestGoal(n), feedback_cb=feedback)
    client.wait_for_result(rospy.Duration(20))
    state = NAMES.get(client.get_state(), str(client.get_state()))
    result = client.get_result()
    value = result.result if result is not None else None
    text = client.get_goal_status_text()
    print(f"result {n} {state} {value} {len(seen)} {text}", flush=True)
