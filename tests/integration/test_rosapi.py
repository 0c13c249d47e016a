"""rosapi's services as ``web/rosapi.RosApi`` answers them, on our master: a graph of our own
nodes, each service asked with and without its leading slash, and each failure. The same
answers beside the real rosapi_node's are ``tests/interop/test_rosapi_interop.py``'s."""

from __future__ import annotations

import asyncio
import json
import time
from collections.abc import Awaitable, Callable
from typing import Any

import pytest

from rostools.msgs.codec import Codec
from rostools.msgs.store import BuiltinSource, TypeStore
from rostools.msgs.topictype import ServiceType, TopicType
from rostools.node.node import LiveNode
from rostools.node.service import ServiceClient
from rostools.web.rosapi import SERVICES, RosApi, RosApiFailure, action_servers
from tests.support.procs import free_port
from tests.support.rosbridge_parity import GOLDEN

STORE = TypeStore([BuiltinSource()])
CODEC = Codec.of(STORE)
for _srv in ("std_srvs/SetBool", "rosapi/GetParam", "rosapi/SetParam"):
    STORE.srv(_srv)  # their request and response messages, for CODEC


def on_graph(master: str, body: Callable[[RosApi, LiveNode], Awaitable[None]]) -> None:
    """``body(api, graph)``: /chatter published, /from_web subscribed, /set_flag served by
    the node /rosapi_graph, and a RosApi on a node of its own."""

    async def main() -> None:
        # no logger services: the node_details below are those of a node without them
        graph = await LiveNode("rosapi_graph", master, logger_services=False).start()
        node = await LiveNode("rosapi_test", master).start()
        try:
            await graph.advertise("/chatter", TopicType.of(STORE, "std_msgs/String"))
            await graph.subscribe(
                "/from_web", lambda *_: None, TopicType.of(STORE, "std_msgs/String")
            )
            response = CODEC.message_class("std_srvs/SetBoolResponse")(True, "ok").serialize()
            await graph.advertise_service(
                "/set_flag", ServiceType.of(STORE, "std_srvs/SetBool"), lambda _: response
            )
            await graph.master.set_param("/rosapi_t/greeting", "hello")
            await body(RosApi(node, STORE), graph)
        finally:
            await node.close()
            await graph.close()

    asyncio.run(main())


async def both(api: RosApi, name: str, args: dict[str, Any]) -> dict[str, Any]:
    """The answer to ``/rosapi/NAME``, checked equal to that of ``rosapi/NAME``.

    The master is shared with other tests, whose topics come and go between two calls: the
    two names must agree on one of three tries, each pair asked back to back.
    """
    for _ in range(3):
        first = await api.call(f"/rosapi/{name}", args)
        second = await api.call(f"rosapi/{name}", args)
        if second == first:
            break
    assert second == first
    return first


def test_handles_rosapi_names_with_and_without_the_slash() -> None:
    api = RosApi(None, STORE)  # type: ignore[arg-type]  # no graph is asked
    for short in SERVICES:
        assert api.handles(f"/rosapi/{short}") and api.handles(f"rosapi/{short}")
    assert not api.handles("/rosapi/get_loggers")  # rospy's own, not rosapi's
    assert not api.handles("/other/topics")
    assert len(SERVICES) == 25


def test_graph_answers(rostools_master: str) -> None:
    async def body(api: RosApi, graph: LiveNode) -> None:
        topics = await both(api, "topics", {})
        assert list(topics) == ["topics", "types"]
        found = dict(zip(topics["topics"], topics["types"], strict=True))
        assert found["/chatter"] == "std_msgs/String"
        assert found["/from_web"] == "std_msgs/String"
        raw = await both(api, "topics_and_raw_types", {})
        assert raw["topics"] == topics["topics"]
        text = raw["typedefs_full_text"][raw["topics"].index("/chatter")]
        assert text == STORE.full_text("std_msgs/String")
        assert (
            "/chatter"
            in (await both(api, "topics_for_type", {"type": "std_msgs/String"}))["topics"]
        )
        string = "std_msgs/String"
        for topic, expected in [("/chatter", string), ("/chatter/data", string),
                                ("/chatter/nope", ""), ("chatter", ""), ("/none", "")]:  # fmt: skip
            assert await both(api, "topic_type", {"topic": topic}) == {"type": expected}, topic
        assert await both(api, "publishers", {"topic": "/chatter"}) == {
            "publishers": ["/rosapi_graph"]
        }
        assert await both(api, "subscribers", {"topic": "/from_web"}) == {
            "subscribers": ["/rosapi_graph"]
        }
        nodes = (await both(api, "nodes", {}))["nodes"]
        assert "/rosapi_graph" in nodes and nodes == sorted(nodes)
        details = await both(api, "node_details", {"node": "/rosapi_graph"})
        assert details == {"subscribing": ["/from_web"], "publishing": ["/chatter"],
                           "services": ["/set_flag"]}  # fmt: skip
        # rosnode's names are compared as given: a relative one matches nothing
        assert await both(api, "node_details", {"node": "rosapi_graph"}) == {
            "subscribing": [], "publishing": [], "services": []
        }  # fmt: skip
        assert "/set_flag" in (await both(api, "services", {}))["services"]
        assert await both(api, "service_type", {"service": "/set_flag"}) == {
            "type": "std_srvs/SetBool"
        }
        assert await both(api, "service_type", {"service": "/nope"}) == {"type": ""}
        assert await both(api, "services_for_type", {"type": "std_srvs/SetBool"}) == {
            "services": ["/set_flag"]
        }
        assert await both(api, "service_providers", {"service": "std_srvs/SetBool"}) == {
            "providers": ["/rosapi_graph"]
        }
        assert await both(api, "service_node", {"service": "/set_flag"}) == {
            "node": "/rosapi_graph"
        }
        assert await both(api, "service_node", {"service": "set_flag"}) == {"node": ""}
        for name in ("/set_flag", "set_flag"):  # the master resolves this one
            assert await both(api, "service_host", {"service": name}) == {"host": "127.0.0.1"}
        assert await both(api, "service_host", {"service": "/nope"}) == {"host": ""}
        assert await both(api, "action_servers", {}) == {"action_servers": []}
        for name in ("/rosapi/get_time", "rosapi/get_time"):  # wall time: no /use_sim_time
            before = time.time_ns()
            now = (await api.call(name, {}))["time"]
            at = now["secs"] * 1_000_000_000 + now["nsecs"]
            assert list(now) == ["secs", "nsecs"] and before <= at <= time.time_ns()

    on_graph(rostools_master, body)


def test_parameters(rostools_master: str) -> None:
    async def body(api: RosApi, graph: LiveNode) -> None:
        get = "get_param"
        assert await both(api, get, {"name": "/rosapi_t/greeting"}) == {"value": '"hello"'}
        assert await both(api, get, {"name": "/rosapi_t"}) == {"value": '{"greeting": "hello"}'}
        assert await both(api, get, {"name": "/missing"}) == {"value": "null"}
        assert await both(api, get, {"name": "/missing", "default": "5"}) == {"value": "5"}
        # a default that is not JSON is the string itself
        assert await both(api, get, {"name": "/missing", "default": "abc"}) == {"value": '"abc"'}
        assert (
            await api.call("/rosapi/set_param", {"name": "rel", "value": '{"a": [1.5, "x"]}'}) == {}
        )
        assert await both(api, get, {"name": "/rel"}) == {"value": '{"a": [1.5, "x"]}'}
        await api.call("/rosapi/set_param", {"name": "~priv", "value": "2"})  # rosapi_node's ~
        assert await graph.master.get_param("/rosapi/priv") == 2
        assert await both(api, "has_param", {"name": "rel"}) == {"exists": True}
        assert await both(api, "search_param", {"name": "rosapi_t"}) == {"global_name": "/rosapi_t"}
        assert await both(api, "search_param", {"name": "greeting"}) == {"global_name": ""}
        names = (await both(api, "get_param_names", {}))["names"]
        assert {"/rel/a", "/rosapi/priv", "/rosapi_t/greeting"} <= set(names)
        assert await api.call("rosapi/delete_param", {"name": "/rel"}) == {}
        assert await both(api, "delete_param", {"name": "/rel"}) == {}  # gone: no failure
        assert await both(api, "has_param", {"name": "/rel"}) == {"exists": False}

    on_graph(rostools_master, body)


def test_message_details_as_the_golden_answer() -> None:
    golden = json.loads(GOLDEN.read_text())["rosapi message_details"][0]["values"]
    api = RosApi(None, STORE)  # type: ignore[arg-type]  # no graph is asked
    answer = asyncio.run(api.call("rosapi/message_details", {"type": "geometry_msgs/PoseStamped"}))
    assert answer == golden


def test_typedefs() -> None:
    api = RosApi(None, STORE)  # type: ignore[arg-type]  # no graph is asked

    def details(name: str, args: dict[str, Any]) -> list[dict[str, Any]]:
        values = asyncio.run(api.call(f"/rosapi/{name}", args))
        typedefs: list[dict[str, Any]] = values["typedefs"]
        return typedefs

    status = details("message_details", {"type": "sensor_msgs/NavSatStatus"})[0]
    assert status["constnames"][:3] == ["SERVICE_COMPASS", "SERVICE_GALILEO", "SERVICE_GLONASS"]
    assert status["constvalues"][status["constnames"].index("STATUS_NO_FIX")] == "-1"
    info = details("message_details", {"type": "sensor_msgs/CameraInfo"})[0]
    assert info["fieldarraylen"][4:8] == [0, 9, 9, 12] and info["examples"][4] == "[]"
    marker = details("message_details", {"type": "visualization_msgs/Marker"})
    assert [t["type"] for t in marker][:4] == [
        "visualization_msgs/Marker", "std_msgs/Header", "time", "geometry_msgs/Pose"
    ]  # fmt: skip
    assert "duration" in [t["type"] for t in marker]
    assert details("message_details", {"type": "std_msgs/Bool"})[0]["examples"] == ["False"]
    assert details("message_details", {"type": "int32"}) == []
    assert [t["type"] for t in details("message_details", {"type": "/std_msgs/Duration/"})] == [
        "std_msgs/Duration", "duration"
    ]  # fmt: skip
    request = details("service_request_details", {"type": "std_srvs/SetBool"})
    assert request == [{"type": "std_srvs/SetBoolRequest", "fieldnames": ["data"],
                        "fieldtypes": ["bool"], "fieldarraylen": [-1], "examples": ["False"],
                        "constnames": [], "constvalues": []}]  # fmt: skip
    response = details("service_response_details", {"type": "rosapi/MessageDetails"})
    assert [t["type"] for t in response] == ["rosapi/MessageDetailsResponse", "rosapi/TypeDef"]


def error(service: str, text: str) -> str:
    raw = f"error processing request: {text}".encode()
    return f"service [/rosapi/{service}] responded with an error: {raw!r}"


@pytest.mark.parametrize(
    ("service", "args", "text"),
    [
        ("message_details", {"type": "Header"},
         error("message_details", "Header is not a valid type string")),
        ("message_details", {},
         error("message_details", " is not a valid type string")),
        ("message_details", {"type": "std_msgs/Nope"},
         error("message_details", "Unable to import msg class Nope from package std_msgs. "
               "Caused by module 'std_msgs.msg' has no attribute 'Nope'")),
        ("message_details", {"type": "std_msgs/Char"},
         error("message_details", "'int' object has no attribute '__module__'")),
        ("service_request_details", {"type": "std_srvs/Nope"},
         error("service_request_details", "Unable to import srv class Nope from package "
               "std_srvs. Caused by module 'std_srvs.srv' has no attribute 'Nope'")),
        ("set_param", {"name": "/x", "value": "notjson"},
         error("set_param", "Due to the type flexibility of the ROS parameter server, the value "
               "argument to set_param must be a JSON-formatted string.")),
        ("set_param", {"name": "/x", "value": "null"},
         error("set_param", "cannot marshal None unless allow_none is enabled")),
        ("topics", {"extra": 1}, "Message type rosapi/TopicsRequest does not have a field extra"),
    ],
)  # fmt: skip
def test_failures(service: str, args: dict[str, Any], text: str) -> None:
    api = RosApi(None, STORE)  # type: ignore[arg-type]  # each fails before asking the graph
    for name in (f"/rosapi/{service}", f"rosapi/{service}"):
        with pytest.raises(RosApiFailure) as failed:
            asyncio.run(api.call(name, args))
        assert str(failed.value) == text


def test_an_unknown_package_names_itself() -> None:
    api = RosApi(None, STORE)  # type: ignore[arg-type]
    with pytest.raises(RosApiFailure) as failed:
        asyncio.run(api.call("rosapi/message_details", {"type": "nonexistent/Type"}))
    assert str(failed.value).startswith(
        error("message_details", "Unable to load the manifest for package nonexistent. "
              "Caused by: nonexistent")[:-1]
    )  # fmt: skip


def test_action_servers_as_rosapi_counts_them() -> None:
    kinds = ["cancel", "feedback", "goal", "result", "status"]
    assert action_servers([f"/fib/{k}" for k in kinds] + ["/chatter"]) == ["/fib"]
    # a topic after the fifth, in the same namespace, lists it again (rosapi's count)
    assert action_servers([f"/fib/{k}" for k in kinds] + ["/fib/zzz"]) == ["/fib", "/fib"]
    assert action_servers([f"/fib/{k}" for k in kinds[:4]]) == []
    assert action_servers([f"/a/b/{k}" for k in kinds]) == ["/a/b"]


def test_advertised_services_answer_ros_clients(rostools_master: str) -> None:
    async def body(api: RosApi, graph: LiveNode) -> None:
        await api.advertise()
        try:
            state = await graph.master.system_state()
            served = {name for name, _ in state[2]}
            assert {f"/rosapi/{s}" for s in SERVICES} <= served
            client = ServiceClient(
                graph, "/rosapi/get_param", ServiceType.of(STORE, "rosapi/GetParam")
            )
            request = CODEC.message_class("rosapi/GetParamRequest")("/rosapi_t/greeting", "")
            answer = CODEC.decode("rosapi/GetParamResponse", await client.call(request.serialize()))
            assert answer.value == '"hello"'
            client = ServiceClient(
                graph, "/rosapi/set_param", ServiceType.of(STORE, "rosapi/SetParam")
            )
            request = CODEC.message_class("rosapi/SetParamRequest")("/x", "notjson")
            with pytest.raises(Exception, match="error processing request: Due to the type"):
                await client.call(request.serialize())
        finally:
            await api.unadvertise()
        state = await graph.master.system_state()
        assert not [name for name, _ in state[2] if name.startswith("/rosapi/")]

    on_graph(rostools_master, body)


def test_a_type_learnt_from_a_publisher_has_details() -> None:
    api = RosApi(None, STORE)  # type: ignore[arg-type]  # no graph is asked
    definition = "int32 a\nrosapi_t_pkg/Sub s\n" + "=" * 80 + "\nMSG: rosapi_t_pkg/Sub\nstring t\n"
    with pytest.raises(RosApiFailure, match="Unable to load the manifest for package"):
        asyncio.run(api.call("rosapi/message_details", {"type": "rosapi_t_pkg/Thing"}))
    api.learn("rosapi_t_pkg/Thing", definition)
    typedefs = asyncio.run(api.call("rosapi/message_details", {"type": "rosapi_t_pkg/Thing"}))
    assert [(t["type"], t["fieldtypes"]) for t in typedefs["typedefs"]] == [
        ("rosapi_t_pkg/Thing", ["int32", "rosapi_t_pkg/Sub"]),
        ("rosapi_t_pkg/Sub", ["string"]),
    ]
    assert api._full_text("rosapi_t_pkg/Thing") == definition


def test_a_master_out_of_reach_fails_as_rosbridge_says() -> None:
    """rosbridge asks the master for the service's type before calling rosapi: its words."""
    node = LiveNode("rosapi_test", f"http://127.0.0.1:{free_port()}")  # nothing listens there
    api = RosApi(node, STORE)
    for service, args in [("topics", {}), ("services", {}), ("get_param", {"name": "/a"}),
                           ("search_param", {"name": "a"})]:  # fmt: skip
        with pytest.raises(RosApiFailure) as failed:
            asyncio.run(api.call(f"rosapi/{service}", args))
        assert str(failed.value) == "Unable to communicate with master!", service
