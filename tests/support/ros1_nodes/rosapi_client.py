"""A rospy client of rosapi's services, as a ROS node calls them (not through rosbridge).

Calls /rosapi/topics, /rosapi/get_param (a set parameter, a missing one), /rosapi/message_details
(geometry_msgs/PoseStamped) and a /rosapi/set_param that fails, with rosapi's generated
classes (the rosbridge peer's PYTHONPATH), and prints one line: "answers " and the answers as
JSON (a failure as {"error": text}).
"""

import json

import rospy
from rosapi.srv import GetParam, MessageDetails, SetParam, Topics


def plain(value):
    if hasattr(value, "__slots__"):
        return {name: plain(getattr(value, name)) for name in value.__slots__}
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    return value


def ask(name, srv_type, *args):
    rospy.wait_for_service(name, timeout=30)
    try:
        return plain(rospy.ServiceProxy(name, srv_type)(*args))
    except rospy.ServiceException as e:
        return {"error": str(e)}


rospy.init_node("rosapi_client", anonymous=True)
answers = {
    "topics": ask("/rosapi/topics", Topics),
    "get_param": ask("/rosapi/get_param", GetParam, "/rbs_test/greeting", ""),
    "get_param, missing": ask("/rosapi/get_param", GetParam, "/rbs_test/missing", ""),
    "message_details": ask("/rosapi/message_details", MessageDetails, "geometry_msgs/PoseStamped"),
    "set_param, not JSON": ask("/rosapi/set_param", SetParam, "/rbs_test/x", "not json"),
}
print("answers " + json.dumps(answers), flush=True)
