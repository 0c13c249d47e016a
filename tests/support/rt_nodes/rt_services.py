"""rostools service servers: rospy_tutorials/AddTwoInts on /add_two_ints, std_srvs/SetBool on
/set_bool and std_srvs/Trigger on /trigger.

Run with the project's python. /add_two_ints refuses a negative sum with an error; /set_bool
answers success = data and message "set <data>"; /trigger counts its calls.
"""

from __future__ import annotations

import asyncio
import os

from rostools.errors import ServiceError
from rostools.msgs.codec import Codec
from rostools.msgs.store import BuiltinSource, TypeStore
from rostools.msgs.topictype import ServiceType
from rostools.node.node import LiveNode


async def main() -> None:
    store = TypeStore([BuiltinSource()])
    codec = Codec.of(store)
    node = await LiveNode("rt_services", os.environ["ROS_MASTER_URI"]).start()
    calls = {"trigger": 0}

    def add(request: bytes) -> bytes:
        req = codec.decode("rospy_tutorials/AddTwoIntsRequest", request)
        total = req.a + req.b
        if total < 0:
            raise ServiceError(f"refusing negative sum {total}")
        return codec.message_class("rospy_tutorials/AddTwoIntsResponse")(total).serialize()

    def set_bool(request: bytes) -> bytes:
        data = codec.decode("std_srvs/SetBoolRequest", request).data
        return codec.message_class("std_srvs/SetBoolResponse")(data, f"set {data}").serialize()

    def trigger(request: bytes) -> bytes:
        calls["trigger"] += 1
        message = f"triggered {calls['trigger']}"
        return codec.message_class("std_srvs/TriggerResponse")(True, message).serialize()

    await node.advertise_service(
        "/add_two_ints", ServiceType.of(store, "rospy_tutorials/AddTwoInts"), add
    )
    await node.advertise_service("/set_bool", ServiceType.of(store, "std_srvs/SetBool"), set_bool)
    await node.advertise_service("/trigger", ServiceType.of(store, "std_srvs/Trigger"), trigger)
    print("ready", flush=True)
    await node.shutdown_requested.wait()
    await node.close()


if __name__ == "__main__":
    asyncio.run(main())
