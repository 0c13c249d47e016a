"""rostools' own publisher and subscriber, for throughput benchmarks.

Usage: rt_pubsub.py pub MASTER TOPIC SIZE SECONDS
       rt_pubsub.py sub MASTER TOPIC SECONDS
The publisher sends std_msgs/String (or sensor_msgs/Image for SIZE >= 100000) as fast as the
link takes them, yielding while the socket is backed up rather than dropping. The subscriber
counts from its first message and prints {"messages", "bytes", "seconds"} as JSON.
"""

from __future__ import annotations

import asyncio
import json
import sys
import time

from rostools.msgs.codec import Codec
from rostools.msgs.store import BuiltinSource, TypeStore
from rostools.msgs.topictype import TopicType
from rostools.node.node import LiveNode


async def publish(master: str, topic: str, size: int, seconds: float) -> None:
    store = TypeStore([BuiltinSource()])
    codec = Codec.of(store)
    if size >= 100_000:
        kind = "sensor_msgs/Image"
        msg = codec.message_class(kind)(
            height=1, width=size, encoding="mono8", step=size, data=bytes(size)
        )
    else:
        kind = "std_msgs/String"
        msg = codec.message_class(kind)("x" * max(size - 4, 0))
    node = await LiveNode("rt_pub", master).start()
    pub = await node.advertise(topic, TopicType.of(store, kind), queue_size=1000)
    payload = msg.serialize()
    while pub.subscriber_count == 0:
        await asyncio.sleep(0.01)
    end = time.monotonic() + seconds
    burst = 256 if size < 10_000 else 1
    while time.monotonic() < end:
        link = pub.links[0] if pub.links else None
        if link is None:
            break
        if link.paused:
            await asyncio.sleep(0.0005)
            continue
        for _ in range(burst):
            pub.publish_raw(payload)
        await asyncio.sleep(0)
    await node.close()


async def subscribe(master: str, topic: str, seconds: float) -> None:
    node = await LiveNode("rt_sub", master).start()
    state = {"n": 0, "bytes": 0, "start": 0.0}

    def on_frames(frames: list, conn: object, now: float) -> None:
        if state["start"] == 0.0:
            state["start"] = now
        state["n"] += len(frames)
        state["bytes"] += sum(len(f) for f in frames)

    await node.subscribe(topic, on_frames)
    while state["start"] == 0.0:
        await asyncio.sleep(0.01)
    await asyncio.sleep(seconds)
    elapsed = time.monotonic() - state["start"]
    print(
        json.dumps({"messages": state["n"], "bytes": state["bytes"], "seconds": elapsed}),
        flush=True,
    )
    await node.close()


if __name__ == "__main__":
    role, master, topic = sys.argv[1:4]
    if role == "pub":
        asyncio.run(publish(master, topic, int(sys.argv[4]), float(sys.argv[5])))
    else:
        asyncio.run(subscribe(master, topic, float(sys.argv[4])))
