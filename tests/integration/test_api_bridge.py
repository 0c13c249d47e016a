"""``rostools.bridge()`` and the plugin's ``ros_bridge``: the bridge from a script or a test."""

from __future__ import annotations

import asyncio

import pytest

import rostools
from rostools import Master, Node
from rostools.testing import plugin  # noqa: F401 - the fixtures below are the plugin's
from tests.support.foxglove import Client, ros_string


def test_the_plugin_serves_a_node_of_the_test_to_a_foxglove_client(
    ros_node: Node, ros_bridge: rostools.WebBridge
) -> None:
    ros_node.publish("/api_latched", {"data": "from a test"}, "std_msgs/String")
    assert ros_bridge.url.startswith("ws://127.0.0.1:") and ros_bridge.port > 0
    with Client(ros_bridge.url) as client:
        sub = client.subscribe("/api_latched")
        assert client.receive(sub)[0][1] == ros_string("from a test")
        client.poll(lambda: ros_bridge.clients == 1, 5, "the client counted")


def test_a_bridge_on_the_callers_loop_and_with_a_token() -> None:
    async def scenario(uri: str) -> int:
        async with rostools.bridge(master_uri=uri, token="t0k") as running:
            port = running.port
            url = running.url
        assert running.clients == 0
        return port if url.endswith(str(port)) else -1

    with Master() as master:
        assert asyncio.run(scenario(master.uri)) > 0


def test_a_bridge_without_a_master_says_so() -> None:
    with pytest.raises(rostools.UnreachableError, match="cannot reach the master"):
        rostools.bridge(master_uri="http://127.0.0.1:9").start()


def test_the_api_bridge_speaks_rosbridge_and_keeps_to_one_protocol(
    ros_master: Master, ros_node: Node
) -> None:
    import json

    from websockets.exceptions import InvalidStatus
    from websockets.sync.client import connect

    ros_node.publish("/api_rb", {"data": "latched"}, "std_msgs/String")
    uri = ros_master.uri
    with rostools.bridge(master_uri=uri, protocol="rosbridge") as running:
        with connect(running.url, open_timeout=10) as ws:
            ws.send(json.dumps({"op": "subscribe", "topic": "/api_rb", "type": "std_msgs/String"}))
            got = json.loads(ws.recv(timeout=10))
        assert got == {"op": "publish", "topic": "/api_rb", "msg": {"data": "latched"}}
    with (
        rostools.bridge(master_uri=uri, protocol="foxglove") as running,
        pytest.raises(InvalidStatus),
    ):
        connect(running.url, open_timeout=10)
    with pytest.raises(rostools.UsageError, match="--protocol ros2: choose one of"):
        rostools.bridge(protocol="ros2")
