"""The parity graph's rospy node (run with the system python): /graph_peer.

Publishes geometry_msgs/PointStamped on /point (10 Hz, header stamped now, frame "map"),
sensor_msgs/JointState on /joints (5 Hz: names, positions, an empty effort), and one latched
std_msgs/String on /latched; subscribes to /chatter; serves std_srvs/SetBool on /set_bool
(true: success, "on"; false: refused with an error) and std_srvs/Empty on /empty. Every
value but the stamps and sequence numbers is fixed, so two runs print the same messages.
"""

import rospy
from geometry_msgs.msg import PointStamped
from sensor_msgs.msg import JointState
from std_msgs.msg import String
from std_srvs.srv import Empty, EmptyResponse, SetBool, SetBoolResponse


def set_bool(req):
    if not req.data:
        raise rospy.ServiceException("refused")
    return SetBoolResponse(success=True, message="on")


rospy.init_node("graph_peer")
point = rospy.Publisher("/point", PointStamped, queue_size=10)
joints = rospy.Publisher("/joints", JointState, queue_size=10)
latched = rospy.Publisher("/latched", String, queue_size=1, latch=True)
rospy.Subscriber("/chatter", String, lambda _msg: None)
rospy.Service("/set_bool", SetBool, set_bool)
rospy.Service("/empty", Empty, lambda _req: EmptyResponse())
latched.publish(String(data="latched hello\nsecond line"))
rate = rospy.Rate(10)
tick = 0
print("ready", flush=True)
while not rospy.is_shutdown():
    msg = PointStamped()
    msg.header.stamp = rospy.Time.now()
    msg.header.frame_id = "map"
    msg.point.x, msg.point.y, msg.point.z = 1.0, -2.5, 3.25
    point.publish(msg)
    if tick % 2 == 0:
        js = JointState()
        js.header.stamp = rospy.Time.now()
        js.name = ["shoulder", "elbow"]
        js.position = [0.5, -1.25]
        js.velocity = [0.0, 0.0]
        joints.publish(js)
    tick += 1
    rate.sleep()
