"""The Master and Parameter APIs, called directly (no sockets)."""

from __future__ import annotations

import pytest

from rostools.master.master_api import MasterAPI
from rostools.wire.xmlvalues import Fault

NODE_A = "http://127.0.0.1:40001/"
NODE_B = "http://127.0.0.1:40002/"


@pytest.fixture
def api() -> MasterAPI:
    return MasterAPI("http://localhost:11311/", pid=42)


def test_argument_checks(api: MasterAPI) -> None:
    assert api.call("getPid", ()) == [-1, "missing required caller_id parameter", -1]
    assert api.call("getPid", ("/a", 1)) == [-1, "Error: bad call arity", -1]
    assert api.call("getPid", (5,)) == [-1, "caller_id must be a string", -1]
    assert api.call("registerPublisher", ("/a", "/t", "bad", NODE_A)) == [
        -1,
        "ERROR: parameter [topic_type] is not a valid package resource name",
        [],
    ]
    assert api.call("registerPublisher", ("/a", "/t", "a/B", "ftp://x")) == [
        -1,
        "ERROR: parameter [caller_api] is not an RPC URI",
        [],
    ]
    assert api.call("registerPublisher", ("/a", 5, "a/B", NODE_A))[:2] == [
        -1,
        "ERROR: parameter [topic] must be a non-empty string",
    ]
    assert api.call("shutdown", ("/a",)) == [-1, "Error: bad call arity", 0]
    with pytest.raises(Fault, match='method "nope" is not supported'):
        api.call("nope", ("/a",))


def test_publish_subscribe_and_updates(api: MasterAPI) -> None:
    assert api.call("registerSubscriber", ("/listener", "chatter", "std_msgs/String", NODE_B)) == [
        1,
        "Subscribed to [/chatter]",
        [],
    ]
    answer = api.call("registerPublisher", ("/talker", "/chatter", "std_msgs/String", NODE_A))
    assert answer == [1, "Registered [/talker] as publisher of [/chatter]", [NODE_B]]
    [update] = api.outgoing
    assert (update.uri, update.method, update.args) == (
        NODE_B,
        "publisherUpdate",
        ("/master", "/chatter", [NODE_A]),
    )
    api.outgoing.clear()
    assert api.call("getSystemState", ("/x",)) == [
        1,
        "current system state",
        [[["/chatter", ["/talker"]]], [["/chatter", ["/listener"]]], []],
    ]
    assert api.call("getPublishedTopics", ("/x", "")) == [
        1,
        "current topics",
        [["/chatter", "std_msgs/String"]],
    ]
    assert api.call("unregisterPublisher", ("/talker", "/chatter", NODE_A)) == [
        1,
        "Unregistered [/talker] as provider of [/chatter]",
        1,
    ]
    assert api.outgoing[0].args == ("/master", "/chatter", [])
    assert api.call("unregisterPublisher", ("/talker", "/chatter", NODE_A)) == [
        1,
        "[/talker] is not a registered node",
        0,
    ]
    assert api.call("lookupNode", ("/x", "/talker")) == [-1, "unknown node [/talker]", ""]
    assert api.call("getTopicTypes", ("/x",)) == [
        1,
        "current system state",
        [["/chatter", "std_msgs/String"]],
    ]


def test_topic_type_rules(api: MasterAPI) -> None:
    api.call("registerSubscriber", ("/s", "/t", "*", NODE_B))
    assert api.call("getTopicTypes", ("/x",))[2] == []
    api.call("registerPublisher", ("/p", "/t", "*", NODE_A))
    assert api.call("getTopicTypes", ("/x",))[2] == [["/t", "*"]]
    api.call("registerPublisher", ("/p", "/t", "a/B", NODE_A))
    api.call("registerPublisher", ("/p", "/t", "*", NODE_A))
    assert api.call("getTopicTypes", ("/x",))[2] == [["/t", "a/B"]]


def test_same_name_new_uri_shuts_the_old_node_down(api: MasterAPI) -> None:
    api.call("registerPublisher", ("/n", "/a", "x/Y", NODE_A))
    api.call("registerService", ("/n", "/srv", "rosrpc://h:1", NODE_A))
    api.outgoing.clear()
    api.call("registerSubscriber", ("/n", "/b", "x/Y", NODE_B))
    [shutdown] = api.outgoing
    assert (shutdown.uri, shutdown.method) == (NODE_A, "shutdown")
    assert shutdown.args == ("/master", "[/n] Reason: new node registered with same name")
    state = api.call("getSystemState", ("/x",))[2]
    assert state == [[], [["/b", ["/n"]]], []]


def test_services(api: MasterAPI) -> None:
    api.call("registerService", ("/a", "/add", "rosrpc://h:1", NODE_A))
    api.call("registerService", ("/b", "/add", "rosrpc://h:2", NODE_B))
    assert api.call("lookupService", ("/x", "add")) == [
        1,
        "rosrpc URI: [rosrpc://h:2]",
        "rosrpc://h:2",
    ]
    assert api.call("unregisterService", ("/a", "/add", "rosrpc://h:1")) == [
        1,
        "[rosrpc://h:1] is no longer the current service api handle for [/add]",
        0,
    ]
    assert api.call("unregisterService", ("/b", "/add", "rosrpc://h:2")) == [
        1,
        "Unregistered [/b] as provider of [/add]",
        1,
    ]
    assert api.call("lookupService", ("/x", "/add")) == [-1, "no provider", ""]


def test_parameters(api: MasterAPI) -> None:
    assert api.call("setParam", ("/ns1/node", "rel", 1)) == [1, "parameter /ns1/rel set", 0]
    assert api.call("getParam", ("/x", "/ns1")) == [1, "Parameter [/ns1]", {"rel": 1}]
    assert api.call("getParam", ("/x", "/nope")) == [-1, "Parameter [/nope] is not set", 0]
    assert api.call("hasParam", ("/ns1/node", "rel")) == [1, "/ns1/rel", True]
    assert api.call("searchParam", ("/ns1/sub/node", "rel")) == [1, "Found [/ns1/rel]", "/ns1/rel"]
    assert api.call("searchParam", ("/n", "~p"))[:2] == [0, "Internal failure: invalid key"]
    assert api.call("deleteParam", ("/x", "/nope")) == [-1, "parameter [/nope] is not set", 0]
    assert api.call("setParam", ("/x", "/", 3)) == [
        -1,
        "Error: invalid arguments: cannot set root of parameter tree to non-dictionary",
        0,
    ]
    assert api.call("subscribeParam", ("/n", NODE_A, "/unset")) == [
        1,
        "Subscribed to parameter [/unset]",
        {},
    ]
    api.call("setParam", ("/other", "/unset", 5))
    assert [(c.method, c.args) for c in api.outgoing] == [
        ("paramUpdate", ("/master", "/unset/", 5)),
    ]
    assert api.call("unsubscribeParam", ("/n", NODE_A, "/unset")) == [
        1,
        "Unsubscribe to parameter [/unset]",
        1,
    ]
    assert api.call("lookupNode", ("/x", "/n")) == [-1, "unknown node [/n]", ""]


def test_multicall(api: MasterAPI) -> None:
    calls = [
        {"methodName": "getPid", "params": ["/a"]},
        {"methodName": "nope", "params": []},
        {"methodName": "setParam", "params": ["/a", "/rosdistro", "noetic\n"]},
    ]
    result = api.call("system.multicall", (calls,))
    assert result[0] == [[1, "", 42]]
    assert result[1]["faultCode"] == 1
    assert result[2] == [[1, "parameter /rosdistro set", 0]]


def test_types_go_with_the_last_user(api: MasterAPI) -> None:
    """rosmaster keeps every type forever; we forget one nobody uses (bounded memory)."""
    api.call("registerPublisher", ("/p", "/t", "a/B", NODE_A))
    api.call("registerSubscriber", ("/s", "/t", "a/B", NODE_B))
    api.call("unregisterPublisher", ("/p", "/t", NODE_A))
    assert api.call("getTopicTypes", ("/x",))[2] == [["/t", "a/B"]]
    api.call("unregisterSubscriber", ("/s", "/t", NODE_B))
    assert api.call("getTopicTypes", ("/x",))[2] == []
    api.call("registerPublisher", ("/n", "/u", "a/B", NODE_A))
    api.call("registerSubscriber", ("/n", "/v", "a/B", NODE_B))  # same name, new URI: purged
    assert api.call("getTopicTypes", ("/x",))[2] == [["/v", "a/B"]]
