"""A rospy client of rosbag_snapshot's trigger_snapshot, its type built from the .srv text.

Run with the system python: snapshot_client.py SERVICE BEFORE AFTER NAME [NAME ...]
For each NAME it asks for the window [now - BEFORE, now + AFTER] (rospy time) and prints
``answer SUCCESS START_NS STOP_NS MESSAGE``; the answers come in the order asked.
"""

import sys

import genmsg
import genmsg.gentools
import genmsg.msg_loader
import genpy.dynamic
import rospy

TYPE = "rosbag_snapshot_msgs/TriggerSnapshot"
REQUEST = "string filename\nstring[] topics\ntime start_time\ntime stop_time\n"
RESPONSE = (
    "string NO_DATA_MESSAGE=no messages buffered on selected topics\nbool success\nstring message\n"
)


def service_class():
    """The service class genpy would generate, md5sum computed by genmsg."""
    context = genmsg.MsgContext.create_default()
    spec = genmsg.msg_loader.load_srv_from_string(context, REQUEST + "---\n" + RESPONSE, TYPE)
    classes = {}
    for part, text in (("Request", REQUEST), ("Response", RESPONSE)):
        classes.update(genpy.dynamic.generate_dynamic(TYPE + part, text))

    class TriggerSnapshot:
        _type = TYPE
        _md5sum = genmsg.gentools.compute_md5(context, spec)
        _request_class = classes[TYPE + "Request"]
        _response_class = classes[TYPE + "Response"]

    return TriggerSnapshot


service, before, after = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
rospy.init_node("snapshot_client", anonymous=True)
rospy.wait_for_service(service, timeout=20)
proxy = rospy.ServiceProxy(service, service_class())
for name in sys.argv[4:]:
    now = rospy.Time.now()
    start, stop = now - rospy.Duration(before), now + rospy.Duration(after)
    answer = proxy(filename=name, topics=[], start_time=start, stop_time=stop)
    print(
        f"answer {answer.success} {start.to_nsec()} {stop.to_nsec()} {answer.message}", flush=True
    )
