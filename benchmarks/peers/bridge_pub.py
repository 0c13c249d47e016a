"""Publishes one big stamped message type at a rate, raw bytes patched with the publish time.

usage: bridge_pub.py image|cloud HZ   (ROS_MASTER_URI from the environment)
image: sensor_msgs/Image 1 MB (rgb8 640x546); cloud: sensor_msgs/PointCloud2, 1M points x 16 B.
The header stamp (bytes 4..12 of the message) is the wall time of the publish, so a receiver's
delay is its receive time minus it. Prints "ready" once advertised.
"""

from __future__ import annotations

import asyncio
import os
import struct
import sys
import time

from rostools._api.messages import message, store
from rostools.msgs.topictype import TopicType
from rostools.node.node import LiveNode

STAMP = struct.Struct("<II")


def payload(kind: str) -> tuple[str, str, bytes]:
    """(topic, type, serialised message) of ``kind``."""
    if kind == "image":
        width, height = 640, 546  # 3 x 640 x 546 = 1,048,320 bytes
        data = bytes(3 * width * height)
        msg = message(
            "sensor_msgs/Image",
            {"height": height, "width": width, "encoding": "rgb8", "step": 3 * width, "data": data},
        )
        return "/bench_image", "sensor_msgs/Image", msg.serialize()
    points = 1_000_000
    fields = [{"name": n, "offset": 4 * i, "datatype": 7, "count": 1} for i, n in enumerate("xyz")]
    fields.append({"name": "intensity", "offset": 12, "datatype": 7, "count": 1})
    msg = message(
        "sensor_msgs/PointCloud2",
        {
            "height": 1,
            "width": points,
            "fields": fields,
            "point_step": 16,
            "row_step": 16 * points,
            "data": bytes(16 * points),
            "is_dense": True,
        },
    )
    return "/bench_cloud", "sensor_msgs/PointCloud2", msg.serialize()


async def main(kind: str, hz: float) -> None:
    topic, type_name, raw = payload(kind)
    node = await LiveNode("bench_pub", os.environ["ROS_MASTER_URI"], anonymous_name=True).start()
    pub = await node.advertise(topic, TopicType.of(store(), type_name))
    print("ready", flush=True)
    buf = bytearray(raw)
    period, due = 1.0 / hz, time.monotonic()
    while True:
        now = time.time_ns()
        STAMP.pack_into(buf, 4, now // 1_000_000_000, now % 1_000_000_000)
        pub.publish(bytes(buf))
        due += period
        await asyncio.sleep(max(0.0, due - time.monotonic()))


if __name__ == "__main__":
    asyncio.run(main(sys.argv[1], float(sys.argv[2])))
