"""A rospy AddTwoInts server on /add_two_ints (the tutorial), plus std_srvs/Trigger on /trigger
and on /slow, which answers after the seconds given as the first argument (default 0).

rospy_tutorials is not packaged by Debian, so its classes are generated here from the .srv
definition with genpy, as the build would. Run with the system python: add_two_ints_server.py
A negative sum is refused with rospy.ServiceException, so tests see a failure message.
"""

import sys
import time

import rospy
from genpy.dynamic import generate_dynamic
from std_srvs.srv import Trigger, TriggerResponse

REQUEST = "int64 a\nint64 b\n"
RESPONSE = "int64 sum\n"
req_class = generate_dynamic("rospy_tutorials/AddTwoIntsRequest", REQUEST)[
    "rospy_tutorials/AddTwoIntsRequest"
]
res_class = generate_dynamic("rospy_tutorials/AddTwoIntsResponse", RESPONSE)[
    "rospy_tutorials/AddTwoIntsResponse"
]


class AddTwoInts:
    _type = "rospy_tutorials/AddTwoInts"
    _md5sum = "6a2e34150c00229791cc89ff309fff21"
    _request_class = req_class
    _response_class = res_class


def add(req):
    total = req.a + req.b
    if total < 0:
        raise rospy.ServiceException(f"negative sum {total}")
    return res_class(sum=total)


calls = {"n": 0}


def trigger(_req):
    calls["n"] += 1
    return TriggerResponse(success=True, message=f"triggered {calls['n']}")


def slow(_req):
    time.sleep(float(sys.argv[1]) if len(sys.argv) > 1 else 0.0)
    return TriggerResponse(success=True, message="slowly")


rospy.init_node("add_two_ints_server")
rospy.Service("/add_two_ints", AddTwoInts, add)
rospy.Service("/trigger", Trigger, trigger)
rospy.Service("/slow", Trigger, slow)
print("ready", flush=True)
rospy.spin()
