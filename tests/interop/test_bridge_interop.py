"""``rostools bridge`` with real rospy and roscpp nodes, on rostools core and on a real roscore."""

from __future__ import annotations

import struct
import subprocess
from pathlib import Path

import pytest

from tests.conftest import MasterInfo
from tests.interop.conftest import start_node_peers
from tests.support.env import needs_ros1
from tests.support.foxglove import Client, ros_string, start_bridge
from tests.support.procs import Proc, start_ros1_node, until_printed, wait_for

pytestmark = [pytest.mark.interop, needs_ros1]

ADD = struct.Struct("<qq")


def failure(client: Client, call_id: int) -> dict[str, object]:
    """The serviceCallFailure of call ``call_id``."""
    return client.wait(lambda m: m.get("op") == "serviceCallFailure" and m["callId"] == call_id)


def publish_until(client: Client, channel: int, text: str, node: Proc, seen: str) -> None:
    """Publish ``text`` from the client until ``node`` prints ``seen`` (it may connect late)."""
    until_printed(
        lambda: client.send(b"\x01" + struct.pack("<I", channel) + ros_string(text)), node, seen
    )


def test_rospy_nodes_through_the_bridge(any_master: MasterInfo) -> None:
    env = any_master.ros_env
    talker = start_ros1_node("talker.py", ["/chatter", "20"], env)
    server = start_ros1_node("add_two_ints_server.py", [], env)
    listener = start_ros1_node("listener.py", ["/to_rospy"], env)
    bridge, url = start_bridge(any_master.cli_env)
    try:
        server.expect("ready", 30)
        listener.expect("ready", 30)
        with Client(url) as client:
            channel = client.channel("/chatter", 30)
            assert (channel["schemaName"], channel["schema"]) == (
                "std_msgs/String",
                "string data\n",
            )
            sub = client.subscribe("/chatter")
            (_, payload), *_ = client.receive(sub, 2, 30)
            assert payload[4:].startswith(b"hello ")

            client.poll(lambda: "/add_two_ints" in client.services, 30, "the service")
            service = client.services["/add_two_ints"]
            assert service["type"] == "rospy_tutorials/AddTwoInts"
            assert service["request"]["schema"] == "int64 a\nint64 b\n"
            client.call("/add_two_ints", ADD.pack(2, 3), call_id=1)
            client.poll(lambda: bool(client.responses()), 30, "a service response")
            assert client.responses() == [(service["id"], 1, struct.pack("<q", 5))]
            client.call("/add_two_ints", ADD.pack(-5, 1), call_id=2)
            assert "negative sum -4" in str(failure(client, 2)["message"])

            client.send(
                {
                    "op": "advertise",
                    "channels": [
                        {
                            "id": 1,
                            "topic": "/to_rospy",
                            "encoding": "ros1",
                            "schemaName": "std_msgs/String",
                            "schema": "string data\n",
                        }
                    ],
                }
            )
            publish_until(client, 1, "from the web", listener, "got from the web")

            client.send({"op": "subscribeParameterUpdates", "parameterNames": ["/gain"]})

            def updated() -> bool:
                subprocess.run(["rosparam", "set", "/gain", "3"], env=env, check=True, timeout=30)
                try:
                    client.wait(lambda m: m.get("op") == "parameterValues", 2)
                except AssertionError:
                    return False
                return True

            wait_for(updated, 30, "a paramUpdate from the master")
    finally:
        bridge.stop()
        for proc in (talker, server, listener):
            proc.stop()


def test_roscpp_nodes_through_the_bridge(
    any_master: MasterInfo, node_peers: dict[str, Path]
) -> None:
    env = any_master.ros_env
    talker, listener, server = start_node_peers(node_peers, env)
    bridge, url = start_bridge(any_master.cli_env)
    try:
        for proc in (talker, listener, server):
            proc.expect("ready", 30)
        with Client(url) as client:
            sub = client.subscribe("/cpp_chatter")
            (_, payload), *_ = client.receive(sub, 2, 30)
            assert payload[4:].startswith(b"hello ")
            client.poll(lambda: "/add_two_ints" in client.services, 30, "the service")
            client.call("/add_two_ints", ADD.pack(1, 2), call_id=9)
            assert str(failure(client, 9)["message"]).endswith("was told to throw")  # its exception
            client.send(
                {
                    "op": "advertise",
                    "channels": [
                        {
                            "id": 4,
                            "topic": "/to_roscpp",
                            "encoding": "ros1",
                            "schemaName": "std_msgs/String",
                        }
                    ],
                }
            )  # no schema: the store's
            publish_until(client, 4, "to roscpp", listener, "got to roscpp")
    finally:
        bridge.stop()
        for proc in (talker, listener, server):
            proc.stop()
