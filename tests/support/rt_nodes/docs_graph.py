"""The graph the docs' examples assume, for tests/integration/test_doc_examples.py.

Run with the project's python, with ``ROSTOOLS_MSG_PATH`` naming ``tests/support/doc_types``
(turtlesim/Spawn and actionlib_tutorials/Fibonacci, installed nowhere else: the examples
learn them from these servers). Prints "ready" once everything is advertised.

- topics: /chatter, /odom, /cmd_vel, /scan, /imu (500 Hz), /camera/image, /heartbeat, /tf;
- services: /add_two_ints, /reset (std_srvs/SetBool), /spawn (turtlesim/Spawn);
- the action /fib (actionlib_tutorials/Fibonacci): feedback every 20 ms;
- subscribers of /cmd_vel and /goal, as a robot's would be.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import time
from typing import Any

from rostools._api.messages import message, store
from rostools.action.server import ActionServer, ServerGoalHandle
from rostools.action.types import ActionTypes
from rostools.msgs.codec import Codec
from rostools.msgs.topictype import ServiceType, TopicType
from rostools.node.node import LiveNode
from rostools.node.publisher import TopicPublisher

#: topic -> (type, rate in Hz)
TOPICS = {
    "/chatter": ("std_msgs/String", 10),
    "/odom": ("nav_msgs/Odometry", 20),
    "/cmd_vel": ("geometry_msgs/Twist", 10),
    "/scan": ("sensor_msgs/LaserScan", 10),
    "/imu": ("sensor_msgs/Imu", 500),
    "/camera/image": ("sensor_msgs/Image", 5),
    "/heartbeat": ("std_msgs/String", 5),
    "/tf": ("tf2_msgs/TFMessage", 10),
}


def sample(topic: str, n: int) -> dict[str, Any]:
    """The ``n``-th message on ``topic``, as a dict."""
    header = {"seq": n, "stamp": "now", "frame_id": "base_link"}
    x = 0.01 * (n % 1000)
    if topic == "/odom":
        return {
            "header": {**header, "frame_id": "odom"},
            "child_frame_id": "base_link",
            "pose": {"pose": {"position": {"x": x, "y": 2 * x}, "orientation": {"w": 1.0}}},
            "twist": {"twist": {"linear": {"x": 0.5}, "angular": {"z": 0.1}}},
        }
    if topic == "/cmd_vel":
        return {"linear": {"x": 0.5}, "angular": {"z": 0.1}}
    if topic == "/scan":
        return {
            "header": header, "angle_min": -1.0, "angle_max": 1.0, "angle_increment": 0.25,
            "range_min": 0.2, "range_max": 10.0, "ranges": [1.0 + x] * 9,
        }  # fmt: skip
    if topic == "/imu":
        return {"header": header, "linear_acceleration": {"x": 0.1, "y": 0.0, "z": 9.81 + x}}
    if topic == "/camera/image":
        return {"header": header, "height": 4, "width": 4, "encoding": "mono8", "step": 4,
                "data": bytes(range(16))}  # fmt: skip
    if topic == "/tf":
        return {"transforms": [{"header": {**header, "frame_id": "odom"},
                                "child_frame_id": "base_link",
                                "transform": {"translation": {"x": x},
                                              "rotation": {"w": 1.0}}}]}  # fmt: skip
    if topic == "/heartbeat":
        return {"data": "alive"}
    return {"data": f"hello world {n}"}


async def publish(pub: TopicPublisher, topic: str, type_name: str, rate: int) -> None:
    """Publish ``topic`` at ``rate`` Hz until cancelled."""
    period = 1 / rate
    n = 0
    next_at = time.monotonic()
    while True:
        pub.publish(message(type_name, sample(topic, n)).serialize())
        n += 1
        next_at += period
        await asyncio.sleep(max(0.0, next_at - time.monotonic()))


async def serve_fib(node: LiveNode) -> ActionServer:
    """/fib: the Fibonacci sequence up to ``order``, a feedback per number."""
    types = ActionTypes(store(), "actionlib_tutorials/FibonacciAction")

    async def execute(goal: ServerGoalHandle) -> object:
        sequence = [0, 1]
        for _ in range(1, goal.goal.order):
            if goal.cancel_requested.is_set():
                goal.canceled(types.message("Result", sequence=sequence))
                return None
            sequence.append(sequence[-1] + sequence[-2])
            goal.publish_feedback(sequence=list(sequence))
            with contextlib.suppress(asyncio.TimeoutError):
                await asyncio.wait_for(goal.cancel_requested.wait(), 0.02)
        return types.message("Result", sequence=sequence)

    return await ActionServer(node, "/fib", types, execute).start()


async def main() -> None:
    types = store()
    node = await LiveNode("docs_graph", os.environ["ROS_MASTER_URI"]).start()
    ignore: Any = lambda *_: None  # noqa: E731 - the robot's subscribers only listen

    codec = Codec.of(types)

    def add(request: bytes) -> bytes:
        req = codec.decode("rospy_tutorials/AddTwoIntsRequest", request)
        return message("rospy_tutorials/AddTwoIntsResponse", {"sum": req.a + req.b}).serialize()

    def reset(request: bytes) -> bytes:
        done = codec.decode("std_srvs/SetBoolRequest", request).data
        answer = {"success": True, "message": "reset" if done else "not reset"}
        return message("std_srvs/SetBoolResponse", answer).serialize()

    def spawn(request: bytes) -> bytes:
        name = codec.decode("turtlesim/SpawnRequest", request).name or "turtle2"
        return message("turtlesim/SpawnResponse", {"name": name}).serialize()

    tasks = []
    for topic, (type_name, rate) in TOPICS.items():
        pub = await node.advertise(topic, TopicType.of(types, type_name))
        tasks.append(asyncio.create_task(publish(pub, topic, type_name, rate)))
    await node.subscribe("/goal", ignore, TopicType.of(types, "geometry_msgs/PoseStamped"))
    await node.subscribe("/cmd_vel", ignore, TopicType.of(types, "geometry_msgs/Twist"))
    await node.advertise_service(
        "/add_two_ints", ServiceType.of(types, "rospy_tutorials/AddTwoInts"), add
    )
    await node.advertise_service("/reset", ServiceType.of(types, "std_srvs/SetBool"), reset)
    await node.advertise_service("/spawn", ServiceType.of(types, "turtlesim/Spawn"), spawn)
    server = await serve_fib(node)
    print("ready", flush=True)
    await node.shutdown_requested.wait()
    for task in tasks:
        task.cancel()
    await server.close()
    await node.close()


if __name__ == "__main__":
    asyncio.run(main())
