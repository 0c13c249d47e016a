"""A persistent rospy ServiceProxy calling std_srvs/SetBool on /set_bool N times, then
std_srvs/Trigger once; prints each answer. Run with the system python: service_proxy_client.py N
"""

import sys

import rospy
from std_srvs.srv import SetBool, Trigger

n = int(sys.argv[1])
rospy.wait_for_service("/set_bool", timeout=20)
proxy = rospy.ServiceProxy("/set_bool", SetBool, persistent=True)
for i in range(n):
    answer = proxy(data=(i % 2 == 0))
    print(f"answer {answer.success} {answer.message}", flush=True)
proxy.close()
print(f"trigger {rospy.ServiceProxy('/trigger', Trigger)().message}", flush=True)
