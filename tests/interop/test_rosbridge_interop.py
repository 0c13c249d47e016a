"""rosbridge v2 on ``rostools bridge`` with real rospy and roscpp nodes, on rostools core and on
a real roscore: subscribe (JSON and cbor-raw), publish, service calls both ways."""

from __future__ import annotations

from pathlib import Path

import pytest
from websockets.sync.client import connect

from tests.conftest import MasterInfo
from tests.interop.conftest import start_node_peers
from tests.support.env import needs_ros1
from tests.support.foxglove import start_bridge
from tests.support.load import scaled
from tests.support.procs import Proc, start_ros1_node, until_printed
from tests.support.rosbridge_parity import Session, _is

pytestmark = [pytest.mark.interop, needs_ros1]


def rosbridge(url: str) -> Session:
    """A rosbridge client session (no subprotocol offered)."""
    ws = connect(url, open_timeout=scaled(10), max_size=None, compression=None)
    ws.__enter__()  # closed by the test's ``close``
    return Session(ws)


def publish_until(s: Session, topic: str, text: str, node: Proc, seen: str) -> None:
    """Publish ``text`` until ``node`` prints ``seen`` (its subscriber may connect late)."""
    until_printed(
        lambda: s.send({"op": "publish", "topic": topic, "msg": {"data": text}}), node, seen
    )


def test_rospy_nodes_through_rosbridge(any_master: MasterInfo) -> None:
    env = any_master.ros_env
    talker = start_ros1_node("talker.py", ["/chatter", "20"], env)
    server = start_ros1_node("add_two_ints_server.py", [], env)
    listener = start_ros1_node("listener.py", ["/to_rospy"], env)
    bridge, url = start_bridge(any_master.cli_env)
    procs = [talker, server, listener]
    s = rosbridge(url)
    try:
        server.expect("ready", 30)
        listener.expect("ready", 30)
        s.send({"op": "subscribe", "topic": "/chatter", "type": "std_msgs/String"})
        assert s.until(_is("publish", topic="/chatter"), 30)["msg"]["data"].startswith("hello ")

        s.send({"op": "call_service", "id": "sum", "service": "/add_two_ints",
                "args": {"a": 2, "b": 3}})  # fmt: skip
        assert s.until(_is("service_response", id="sum"), 30)["values"] == {"sum": 5}
        s.send({"op": "call_service", "id": "neg", "service": "/add_two_ints", "args": [-5, 1]})
        failed = s.until(_is("service_response", id="neg"), 30)
        assert not failed["result"] and "negative sum -4" in failed["values"]

        s.send({"op": "advertise", "topic": "/to_rospy", "type": "std_msgs/String"})
        publish_until(s, "/to_rospy", "from the web", listener, "got from the web")

        # a web client serves two services; a persistent rospy ServiceProxy calls them
        s.send({"op": "advertise_service", "service": "/set_bool", "type": "std_srvs/SetBool"})
        s.send({"op": "advertise_service", "service": "/trigger", "type": "std_srvs/Trigger"})
        client = start_ros1_node("service_proxy_client.py", ["3"], env)
        procs.append(client)
        for n in range(1, 4):
            call = s.until(_is("call_service", service="/set_bool"), 30)
            assert call["id"] == f"service_request:/set_bool:{n}"
            s.send({"op": "service_response", "service": "/set_bool", "id": call["id"],
                    "result": True, "values": {"success": call["args"]["data"],
                                               "message": f"web {n}"}})  # fmt: skip
            client.expect(f"answer (True|False) web {n}", 30)
        call = s.until(_is("call_service", service="/trigger"), 30)
        s.send({"op": "service_response", "service": "/trigger", "id": call["id"],
                "result": True, "values": {"success": True, "message": "fired"}})  # fmt: skip
        client.expect("trigger fired", 30)
    finally:
        s.ws.close()
        bridge.stop()
        for proc in procs:
            proc.stop()


def test_roscpp_nodes_through_rosbridge(
    any_master: MasterInfo, node_peers: dict[str, Path]
) -> None:
    env = any_master.ros_env
    talker, listener, server = start_node_peers(node_peers, env)
    bridge, url = start_bridge(any_master.cli_env)
    s = rosbridge(url)
    try:
        for proc in (talker, listener, server):
            proc.expect("ready", 30)
        s.send({"op": "subscribe", "topic": "/cpp_chatter", "compression": "cbor-raw"})
        raw = s.until(lambda m: "cbor" in m, 30)["cbor"]["msg"]
        assert bytes.fromhex(raw["bytes"]["bytes"])[4:].startswith(b"hello ")
        # a client's subscriptions to a topic share the strongest compression, as rosbridge's:
        # JSON needs the cbor-raw one gone
        s.send({"op": "unsubscribe", "topic": "/cpp_chatter"})
        s.send({"op": "subscribe", "topic": "/cpp_chatter", "id": "json"})  # its type: learnt
        text = s.until(lambda m: m.get("op") == "publish", 30)["msg"]["data"]  # JSON, not CBOR
        assert text.startswith("hello ")
        s.send({"op": "call_service", "id": "c", "service": "/add_two_ints", "args": [1, 2]})
        failed = s.until(_is("service_response", id="c"), 30)
        assert not failed["result"] and str(failed["values"]).endswith("was told to throw")
        s.send({"op": "advertise", "topic": "/to_roscpp", "type": "std_msgs/String"})
        publish_until(s, "/to_roscpp", "to roscpp", listener, "got to roscpp")
    finally:
        s.ws.close()
        bridge.stop()
        for proc in (talker, listener, server):
            proc.stop()
