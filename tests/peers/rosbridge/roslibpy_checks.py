"""roslibpy (2.1.0, from PyPI) against a rosbridge v2 server with
``tests/support/ros1_nodes/rosbridge_graph.py`` on its graph: the checks a roslibpy script makes.

usage: python roslibpy_checks.py HOST PORT [SCALE]   (SCALE multiplies every deadline)

One JSON line per check, then a summary line; exits 1 if any check failed. A process of its
own: roslibpy runs Twisted's reactor, which starts once per process.
"""

from __future__ import annotations

import json
import sys
import threading
from collections.abc import Callable
from typing import Any

import roslibpy

host, port = sys.argv[1], int(sys.argv[2])
scale = float(sys.argv[3]) if len(sys.argv) > 3 else 1.0
results: list[bool] = []
# the deadline of roslibpy's blocking rosapi calls (get_topics, get_param, ...)
roslibpy.set_rosapi_timeout(10 * scale)


def check(name: str, run: Callable[[], tuple[bool, Any]]) -> None:
    """Run one check; print its line."""
    try:
        ok, detail = run()
    except Exception as e:  # noqa: BLE001 (a check's failure, whatever it is, is printed)
        ok, detail = False, f"{type(e).__name__}: {e}"
    results.append(ok)
    print(json.dumps({"check": name, "ok": ok, "detail": detail}, default=repr), flush=True)


ros = roslibpy.Ros(host=host, port=port)
ros.run()
check("connect", lambda: (ros.is_connected, f"{host}:{port}"))


def topics() -> tuple[bool, Any]:
    names = ros.get_topics()
    return "/chatter" in names, names


check("get_topics", topics)
check("get_topic_type", lambda: (
    (t := ros.get_topic_type("/chatter")) == "std_msgs/String", t))  # fmt: skip
check("get_services", lambda: (
    "/set_flag" in (s := ros.get_services()), s))  # fmt: skip
check("get_nodes", lambda: ("/rbs_ros_side" in (n := ros.get_nodes()), n))


def params() -> tuple[bool, Any]:
    greeting = ros.get_param("/rbs_test/greeting")
    ros.set_param("/rbs_test/from_roslibpy", {"a": 1, "b": [1.5, "x"]})
    back = ros.get_param("/rbs_test/from_roslibpy")
    return greeting == "hello from rosparam" and back == {"a": 1, "b": [1.5, "x"]}, [greeting, back]


check("get_param and set_param", params)


def subscribe() -> tuple[bool, Any]:
    got: list[str] = []
    five = threading.Event()

    def on(m: dict[str, Any]) -> None:
        got.append(m["data"])
        if len(got) >= 5:
            five.set()

    chatter = roslibpy.Topic(ros, "/chatter", "std_msgs/String")
    chatter.subscribe(on)
    five.wait(20 * scale)
    chatter.unsubscribe()
    return len(got) >= 5 and all(d.startswith("hello ") for d in got), got[:5]


check("subscribe", subscribe)

echoes: list[str] = []
echoed = threading.Condition()


def on_echo(m: dict[str, Any]) -> None:
    with echoed:
        echoes.append(m["data"])
        echoed.notify_all()


def wait_echo(match: Callable[[str], bool], timeout: float) -> str | None:
    with echoed:
        echoed.wait_for(lambda: any(match(e) for e in echoes), timeout * scale)
        return next((e for e in echoes if match(e)), None)


roslibpy.Topic(ros, "/from_web_echo", "std_msgs/String").subscribe(on_echo)
pub = roslibpy.Topic(ros, "/from_web", "std_msgs/String")
pub.advertise()


def publish() -> tuple[bool, Any]:
    # again and again until rospy's subscriber has connected to the server's new publisher
    for _ in range(80):  # 20 s on a quiet machine: wait_echo's 0.25 s is scaled
        pub.publish(roslibpy.Message({"data": "hi from roslibpy"}))
        if got := wait_echo(lambda e: e == "rospy got: hi from roslibpy", 0.25):
            return True, got
    return False, echoes[-3:]


check("publish, rospy echoes it", publish)


def call() -> tuple[bool, Any]:
    service = roslibpy.Service(ros, "/set_flag", "std_srvs/SetBool")
    r = service.call(roslibpy.ServiceRequest({"data": False}))
    return r["success"] is False and r["message"] == "flag=False", dict(r)


check("call_service", call)


def missing() -> tuple[bool, Any]:
    service = roslibpy.Service(ros, "/no_such_service", "std_srvs/SetBool")
    try:
        r = service.call(roslibpy.ServiceRequest({"data": True}))
    except Exception as e:  # noqa: BLE001 (roslibpy raises a bare Exception for a failed call)
        return "Service /no_such_service does not exist" in str(e), str(e)
    return False, dict(r)


check("call_service, a missing service fails", missing)


def advertise_service() -> tuple[bool, Any]:
    def handler(request: dict[str, Any], response: dict[str, Any]) -> bool:
        response["success"] = request["data"]
        response["message"] = "web says ok"
        return True

    service = roslibpy.Service(ros, "/web_setbool", "std_srvs/SetBool")
    service.advertise(handler)
    pub.publish(roslibpy.Message({"data": "call /web_setbool"}))
    said = wait_echo(lambda e: e.startswith("web service"), 40)
    service.unadvertise()
    return said == "web service said: web says ok", said


check("advertise_service, rospy calls it", advertise_service)

ros.terminate()
failed = results.count(False)
print(json.dumps({"summary": True, "passed": len(results) - failed, "failed": failed}))
sys.exit(1 if failed else 0)
