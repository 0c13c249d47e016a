"""foxglove-sdk's WebSocket server (Rust, 0.30) fed a ROS topic's bytes by a rostools subscriber.

usage: sdk_server.py PORT TOPIC TYPE   (prints "ready" once it serves)
Each TCPROS frame is logged to an SDK channel as it is: message encoding ros1, the type's
ros1msg definition as the schema. So it and rostools bridge are fed the same bytes.
"""

from __future__ import annotations

import asyncio
import os
import sys
import time

import foxglove

from rostools._api.messages import store
from rostools.msgs.topictype import TopicType
from rostools.node.node import LiveNode


async def main(port: int, topic: str, type_name: str) -> None:
    kind = TopicType.of(store(), type_name)
    server = foxglove.start_server(host="127.0.0.1", port=port)
    schema = foxglove.Schema(name=type_name, encoding="ros1msg", data=kind.definition.encode())
    channel = foxglove.Channel(topic, schema=schema, message_encoding="ros1")
    node = await LiveNode("bench_sdk", os.environ["ROS_MASTER_URI"], anonymous_name=True).start()

    def frames(batch: list[bytes | memoryview], conn: object, now: float) -> None:
        for frame in batch:
            channel.log(bytes(frame), log_time=time.time_ns())

    await node.subscribe(topic, frames)
    print("ready", flush=True)
    try:
        await asyncio.Event().wait()
    finally:
        server.stop()


if __name__ == "__main__":
    asyncio.run(main(int(sys.argv[1]), sys.argv[2], sys.argv[3]))
