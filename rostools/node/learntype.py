"""Learning a topic's type from its publishers: subscribe with ``*`` and read the header.

This is how rostools handles types it has never seen: the publisher's connection header
carries the full definition.
"""

from __future__ import annotations

import asyncio

from rostools.errors import TimeoutExpired
from rostools.msgs.topictype import TopicType
from rostools.node.connection import InboundConnection
from rostools.node.node import LiveNode


async def learn_topic_type(node: LiveNode, topic: str, timeout: float) -> TopicType:
    """The type one publisher of ``topic`` announces."""
    found: asyncio.Future[TopicType] = asyncio.get_running_loop().create_future()

    def on_header(conn: InboundConnection) -> None:
        if not found.done() and conn.header is not None:
            found.set_result(TopicType.from_header(conn.header))

    sub = await node.subscribe(topic, lambda *_: None, on_header=on_header)
    try:
        return await asyncio.wait_for(found, timeout)
    except asyncio.TimeoutError:
        raise TimeoutExpired(f"no publisher of {topic} answered within {timeout:g} s") from None
    finally:
        await node.unsubscribe(sub.topic)
