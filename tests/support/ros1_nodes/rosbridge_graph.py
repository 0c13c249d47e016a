"""The ROS side of the rosbridge tests: one rospy node, ``/rbs_ros_side``, on the system python.

- a talker: std_msgs/String "hello N" on /chatter at 10 Hz;
- /set_flag (std_srvs/SetBool): success = data, message = "flag=<data>";
- an echo: each std_msgs/String on /from_web is republished on /from_web_echo as
  "rospy got: <data>";
- "call /web_setbool" on /from_web makes it call /web_setbool (std_srvs/SetBool, served by a
  web client through advertise_service) and publish "web service said: <message>" on
  /from_web_echo;
- the parameter /rbs_test/greeting = "hello from rosparam".

Prints "ready" once all of it is registered.
"""

import threading

import rospy
from std_msgs.msg import String
from std_srvs.srv import SetBool, SetBoolResponse

rospy.init_node("rbs_ros_side")
echo = rospy.Publisher("/from_web_echo", String, queue_size=10)
chatter = rospy.Publisher("/chatter", String, queue_size=10)
rospy.Service(
    "/set_flag", SetBool, lambda req: SetBoolResponse(success=req.data, message=f"flag={req.data}")
)


def call_web():
    try:
        rospy.wait_for_service("/web_setbool", timeout=30)
        answer = rospy.ServiceProxy("/web_setbool", SetBool)(True)
        echo.publish(String(data=f"web service said: {answer.message}"))
    except (rospy.ROSException, rospy.ServiceException) as e:  # said where the test reads
        echo.publish(String(data=f"web service failed: {e}"))


def on_msg(m):
    if m.data == "call /web_setbool":
        threading.Thread(target=call_web, daemon=True).start()
    else:
        echo.publish(String(data="rospy got: " + m.data))


rospy.Subscriber("/from_web", String, on_msg)
rospy.set_param("/rbs_test/greeting", "hello from rosparam")
print("ready", flush=True)
rate, n = rospy.Rate(10), 0
while not rospy.is_shutdown():
    chatter.publish(String(data=f"hello {n}"))
    n += 1
    try:
        rate.sleep()
    except rospy.ROSInterruptException:
        break
