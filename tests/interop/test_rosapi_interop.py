"""rosapi's services as ``web/rosapi.RosApi`` answers them, beside the real rosapi_node 0.11.17.

On one ``rosmaster --core`` with ``rosbridge_graph.py`` (a rospy talker, service, echo and
parameter), each call goes to the real rosapi through the real rosbridge_server, then to our
``RosApi`` on a node of its own, and the two answers must be the same values, or the same
failure text. Names that are the servers' own (rosbridge's and rosapi's nodes, topics,
services and parameters, and our node) are left out; name lists are compared sorted, as the
master gives them in any order. Then a rospy client calls ``/rosapi/*`` as ROS services:
first rosapi_node's, then ours (``RosApi.advertise``), and gets the same answers.
"""

from __future__ import annotations

import asyncio
import json
import re
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
from websockets.sync.client import ClientConnection, connect

from rostools.msgs.store import TypeStore
from rostools.node.node import LiveNode
from rostools.web.rosapi import RosApi, RosApiFailure
from tests.support.load import scaled
from tests.support.procs import ros_env, start_ros1_node
from tests.support.rosbridge import (
    prepare,
    rosbridge_graph,
    rosbridge_missing,
    start_rosbridge,
    start_rosmaster,
)

pytestmark = [pytest.mark.interop]

OURS = "/rosapi_ours"
#: Nodes, topics and name prefixes of the servers themselves, left out of every answer.
OWN_NAMES = {"/rosapi", "/rosbridge_websocket", OURS, "/client_count", "/connected_clients"}
OWN_PREFIXES = ("/rosapi/", "/rosbridge_websocket/", f"{OURS}/", "/rosapi_client")

#: (service, args), asked in this order of both (parameters change along the way).
CALLS: list[tuple[str, dict[str, Any]]] = [
    ("topics", {}),
    ("topics_and_raw_types", {}),
    ("topics_for_type", {"type": "std_msgs/String"}),
    ("topic_type", {"topic": "/chatter"}),
    ("topic_type", {"topic": "/chatter/data"}),
    ("topic_type", {"topic": "/chatter/nope"}),
    ("topic_type", {"topic": "chatter"}),
    ("topic_type", {"topic": "/nope"}),
    ("publishers", {"topic": "/chatter"}),
    ("publishers", {"topic": "/rosout"}),
    ("subscribers", {"topic": "/from_web"}),
    ("nodes", {}),
    ("node_details", {"node": "/rbs_ros_side"}),
    ("node_details", {"node": "rbs_ros_side"}),
    ("action_servers", {}),
    ("services", {}),
    ("service_type", {"service": "/set_flag"}),
    ("service_type", {"service": "set_flag"}),
    ("service_type", {"service": "/nope"}),
    ("services_for_type", {"type": "std_srvs/SetBool"}),
    ("service_providers", {"service": "std_srvs/SetBool"}),
    ("service_node", {"service": "/set_flag"}),
    ("service_node", {"service": "set_flag"}),
    ("service_host", {"service": "/set_flag"}),
    ("service_host", {"service": "set_flag"}),
    ("service_host", {"service": "/nope"}),
    ("get_param", {"name": "/rbs_test/greeting"}),
    ("get_param", {"name": "/rbs_test"}),
    ("get_param", {"name": "/missing"}),
    ("get_param", {"name": "/missing", "default": "5"}),
    ("get_param", {"name": "/missing", "default": "abc"}),
    ("set_param", {"name": "rel", "value": '{"a": 1, "b": [1.5, "x"]}'}),
    ("get_param", {"name": "/rel"}),
    ("set_param", {"name": "~priv", "value": "[1, 2]"}),
    ("get_param", {"name": "~priv"}),
    ("set_param", {"name": "/x", "value": "not json"}),
    ("set_param", {"name": "/x", "value": "null"}),
    ("has_param", {"name": "rel"}),
    ("has_param", {"name": "/nope"}),
    ("search_param", {"name": "rbs_test"}),
    ("search_param", {"name": "greeting"}),
    ("get_param_names", {}),
    ("delete_param", {"name": "/rel"}),
    ("delete_param", {"name": "/rel"}),
    ("has_param", {"name": "/rel"}),
    ("message_details", {"type": "geometry_msgs/PoseStamped"}),
    ("message_details", {"type": "sensor_msgs/NavSatStatus"}),
    ("message_details", {"type": "sensor_msgs/CameraInfo"}),
    ("message_details", {"type": "visualization_msgs/Marker"}),
    ("message_details", {"type": "rosgraph_msgs/Log"}),
    ("message_details", {"type": "std_msgs/Duration"}),
    ("message_details", {"type": "sensor_msgs/Image"}),
    ("message_details", {"type": "std_msgs/Char"}),
    ("message_details", {"type": "time"}),
    ("message_details", {"type": "int32"}),
    ("message_details", {"type": "/std_msgs/Bool/"}),
    ("message_details", {"type": "Header"}),
    ("message_details", {"type": "std_msgs/Nope"}),
    ("message_details", {"type": "nonexistent/Type"}),
    ("message_details", {}),
    ("service_request_details", {"type": "std_srvs/SetBool"}),
    ("service_request_details", {"type": "nav_msgs/GetPlan"}),
    ("service_response_details", {"type": "rosapi/MessageDetails"}),
    ("service_response_details", {"type": "std_srvs/Empty"}),
    ("service_response_details", {"type": "bad/Type"}),
    ("topics", {"extra": 1}),
]


def owned(name: Any) -> bool:
    """Whether ``name`` is one of the servers' own."""
    return isinstance(name, str) and (name in OWN_NAMES or name.startswith(OWN_PREFIXES))


def comparable(values: Any) -> Any:
    """An answer with the servers' own names left out and name lists sorted; a failure's
    text without rospkg's list of ROS paths (each host's own)."""
    if isinstance(values, str):
        return re.sub(r"\\nROS path \[\d+\]=[^\\']*", "", values)
    out = dict(values)
    if "topics" in out and "types" in out:
        rows = zip(
            *(out[k] for k in ("topics", "types", "typedefs_full_text") if k in out), strict=True
        )
        kept = sorted(row for row in rows if not owned(row[0]))
        for i, key in enumerate(k for k in ("topics", "types", "typedefs_full_text") if k in out):
            out[key] = [row[i] for row in kept]
    for key, value in out.items():
        if key not in ("topics", "types", "typedefs_full_text", "typedefs") and isinstance(
            value, list
        ):
            out[key] = sorted(v for v in value if not owned(v))
    return out


@pytest.fixture
def graph(tmp_path: Path) -> Iterator[tuple[str, str]]:
    """A ``rosmaster --core`` with the rosbridge test graph and the real rosbridge_server
    and rosapi_node: the master's URI and the server's URL."""
    if reason := rosbridge_missing():
        pytest.skip(reason)
    master, uri = start_rosmaster(tmp_path)
    try:
        with rosbridge_graph(uri, tmp_path):
            bridge = start_rosbridge(uri, tmp_path)
            try:
                yield uri, bridge.url
            finally:
                bridge.stop()
    finally:
        master.stop()


def real_call(ws: ClientConnection, ident: str, service: str, args: dict[str, Any]) -> Any:
    """rosbridge's answer to ``call_service``: the values, or the failure's text."""
    ws.send(json.dumps({"op": "call_service", "service": service, "args": args, "id": ident}))
    deadline = time.monotonic() + scaled(30)
    while True:
        message = json.loads(ws.recv(timeout=max(0.1, deadline - time.monotonic())))
        if message.get("op") == "service_response" and message.get("id") == ident:
            return message["values"]


def test_answers_as_the_real_rosapi(graph: tuple[str, str]) -> None:
    uri, url = graph

    async def main() -> list[str]:
        node = await LiveNode(OURS.lstrip("/"), uri).start()
        api = RosApi(node, TypeStore.default())
        differences = []
        try:
            with connect(url, open_timeout=scaled(10), max_size=None) as ws:
                for i, (short, args) in enumerate(CALLS):
                    # the real one as roslib 2.x sends it, with no leading slash, and ours both ways
                    real = await asyncio.to_thread(real_call, ws, str(i), f"rosapi/{short}", args)
                    for name in (f"/rosapi/{short}", f"rosapi/{short}"):
                        try:
                            ours: Any = await api.call(name, args)
                        except RosApiFailure as err:
                            ours = str(err)
                        if comparable(ours) != comparable(real):
                            differences.append(f"{name} {args}:\n  real {real}\n  ours {ours}")
                before = time.time_ns()
                real = await asyncio.to_thread(real_call, ws, "time", "/rosapi/get_time", {})
                ours = await api.call("rosapi/get_time", {})
                after = time.time_ns()
                for answer in (real, ours):  # both wall time: no /use_sim_time here
                    stamp = answer["time"]["secs"] * 1_000_000_000 + answer["time"]["nsecs"]
                    assert before - 1_000_000_000 <= stamp <= after, answer
        finally:
            await node.close()
        return differences

    differences = asyncio.run(main())
    assert not differences, "\n".join(differences)


def test_a_rospy_client_gets_the_same_answers(tmp_path: Path) -> None:
    """rospy calls rosapi_node's services, then ours, on the same graph."""
    if reason := rosbridge_missing():
        pytest.skip(reason)
    master, uri = start_rosmaster(tmp_path)
    env = ros_env(uri, tmp_path) | prepare(tmp_path / "rosbridge")

    def client() -> dict[str, Any]:
        proc = start_ros1_node("rosapi_client.py", [], env)
        try:
            answers: dict[str, Any] = json.loads(proc.expect("^answers ", 60)[len("answers ") :])
            return answers
        finally:
            proc.stop()

    try:
        with rosbridge_graph(uri, tmp_path):
            bridge = start_rosbridge(uri, tmp_path)
            try:
                real = client()
            finally:
                bridge.stop()

            async def serve() -> dict[str, Any]:
                node = await LiveNode(OURS.lstrip("/"), uri).start()
                api = RosApi(node, TypeStore.default())
                try:
                    await api.advertise()
                    return await asyncio.to_thread(client)
                finally:
                    await api.unadvertise()
                    await node.close()

            ours = asyncio.run(serve())
    finally:
        master.stop()
    assert "error" not in real["topics"], real
    assert real["message_details"]["typedefs"][0]["type"] == "geometry_msgs/PoseStamped"
    assert "Due to the type flexibility" in real["set_param, not JSON"]["error"]
    assert {k: comparable(v) for k, v in ours.items()} == {
        k: comparable(v) for k, v in real.items()
    }
