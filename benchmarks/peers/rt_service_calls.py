"""Calls per second of persistent rostools service clients: std_srvs/Trigger on /trigger.

Usage: rt_service_calls.py MASTER SECONDS blocking|async   (prints {"calls", "seconds"})
"""

from __future__ import annotations

import asyncio
import json
import sys
import time

from rostools.msgs.store import BuiltinSource, TypeStore
from rostools.msgs.topictype import ServiceType
from rostools.node.node import LiveNode
from rostools.node.service import ServiceClient
from rostools.rosgraph.masterapi import MasterProxy
from rostools.rosgraph.serviceclient import BlockingServiceClient

MD5 = TypeStore([BuiltinSource()]).srv_md5("std_srvs/Trigger")


def blocking(master: str, seconds: float) -> dict[str, float]:
    client = BlockingServiceClient(MasterProxy(master, "/rt_caller"), "/trigger", persistent=True)
    client.call("/rt_caller", MD5, b"")
    calls, start = 0, time.monotonic()
    while time.monotonic() - start < seconds:
        client.call("/rt_caller", MD5, b"")
        calls += 1
    client.close()
    return {"calls": calls, "seconds": time.monotonic() - start}


async def asynchronous(master: str, seconds: float) -> dict[str, float]:
    store = TypeStore([BuiltinSource()])
    node = await LiveNode("rt_caller", master).start()
    client = ServiceClient(
        node, "/trigger", ServiceType.of(store, "std_srvs/Trigger"), persistent=True
    )
    await client.call(b"")
    calls, start = 0, time.monotonic()
    while time.monotonic() - start < seconds:
        await client.call(b"")
        calls += 1
    client.close()
    await node.close()
    return {"calls": calls, "seconds": time.monotonic() - start}


if __name__ == "__main__":
    master, seconds, kind = sys.argv[1], float(sys.argv[2]), sys.argv[3]
    result = (
        blocking(master, seconds)
        if kind == "blocking"
        else asyncio.run(asynchronous(master, seconds))
    )
    print(json.dumps(result), flush=True)
