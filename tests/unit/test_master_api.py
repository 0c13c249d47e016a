"""The Master and Parameter APIs, called directly (no sockets)."""

from __future__ import annotations

import os
from typing import Any

import pytest

from rostools.master.master_api import MasterAPI
from rostools.master.params import MAX_DEPTH
from rostools.wire.xmlvalues import Fault

NODE_A = "http://127.0.0.1:40001/"
NODE_B = "http://127.0.0.1:40002/"
NODE_C = "http://127.0.0.1:40003/"


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


#: One session with a real rosmaster (Noetic, ``rosmaster --core`` on loopback, called in this
#: order with ``xmlrpc.client``), and its answers, captured.
ROSMASTER_SESSION: list[tuple[str, tuple[Any, ...], list[Any]]] = [
    ("getUri", ("/a", 1), [-1, "Error: bad call arity", ""]),
    ("getParamNames", ("/a",), [1, "Parameter names", []]),
    ("setParam", ("/ns/n", "p", 1), [1, "parameter /ns/p set", 0]),
    ("getParamNames", ("/a",), [1, "Parameter names", ["/ns/p"]]),
    ("getParam", ("/ns/n", "p"), [1, "Parameter [/ns/p]", 1]),
    ("subscribeParam", ("/ns/w", NODE_A, "p"), [1, "Subscribed to parameter [/ns/p]", 1]),
    ("lookupNode", ("/x", "/ns/w"), [1, "node api", NODE_A]),
    ("deleteParam", ("/ns/n", "p"), [1, "parameter /ns/p deleted", 0]),
    ("unsubscribeParam", ("/ns/w", NODE_A, "p"), [1, "Unsubscribe to parameter [/ns/p]", 1]),
    ("unsubscribeParam", ("/ns/w", "bad", "p"),
     [-1, "ERROR: parameter [caller_api] is not an RPC URI", 0]),
    ("unregisterService", ("/a", "/s", "bad"),
     [-1, "ERROR: parameter [service_api] is not an RPC URI", 0]),
    ("unregisterService", ("/a", "/s", ""),
     [-1, "ERROR: parameter [service_api] is not an XMLRPC URI", 0]),
    ("unregisterSubscriber", ("/a", "/t", "bad"),
     [-1, "ERROR: parameter [caller_api] is not an RPC URI", 0]),
    ("unregisterPublisher", ("/a", "/t", "bad"),
     [-1, "ERROR: parameter [caller_api] is not an RPC URI", 0]),
    ("registerPublisher", ("/p", "/t", "a/B", NODE_A),
     [1, "Registered [/p] as publisher of [/t]", []]),
    ("registerSubscriber", ("/s", "/t", "a/B", NODE_B), [1, "Subscribed to [/t]", [NODE_A]]),
    ("unregisterService", ("/p", "/nosrv", "rosrpc://h:1"),
     [1, "[/p] is not a provider of [/nosrv]", 0]),
    ("unregisterSubscriber", ("/p", "/other", NODE_A),
     [1, "[/p] is not a known provider of [/other]", 0]),
    ("unregisterSubscriber", ("/p", "/t", NODE_A), [1, "[/p] is not a known provider of [/t]", 0]),
    ("registerService", ("/p", "/srv", "rosrpc://h:1", NODE_A),
     [1, "Registered [/p] as provider of [/srv]", 1]),
    ("searchParam", ("/a", "nope"), [-1, "Cannot find parameter [nope] in an upwards search", ""]),
    ("registerPublisher", ("/m", "/t", "a/B", NODE_C),
     [1, "Registered [/m] as publisher of [/t]", [NODE_B]]),
    # /p again, at a new URI: rosmaster forgets what the old /p registered, and only that
    ("registerSubscriber", ("/p", "/u", "a/B", NODE_B), [1, "Subscribed to [/u]", []]),
    ("getSystemState", ("/x",),
     [1, "current system state", [[["/t", ["/m"]]], [["/t", ["/s"]], ["/u", ["/p"]]], []]]),
    ("shutdown", ("/a", 1, 2), [-1, "Error: bad call arity", 0]),
    ("shutdown", ("/a", "bye"), [1, "shutdown", 0]),
]  # fmt: skip


def test_a_session_answers_as_rosmaster_did(api: MasterAPI) -> None:
    for method, params, answer in ROSMASTER_SESSION:
        assert api.call(method, params) == answer, (method, params)


def test_uri_pid_and_shutdown(api: MasterAPI) -> None:
    assert api.call("getUri", ("/a",)) == [1, "", "http://localhost:11311/"]
    assert MasterAPI("http://h:1/").call("getPid", ("/a",)) == [1, "", os.getpid()]
    # The server stops once this is set: a fresh master has not been asked to.
    assert api.shutdown_requested is None
    api.call("shutdown", ("/a", ""))
    assert api.shutdown_requested == "external shutdown request"
    api.call("shutdown", ("/a", "bye"))
    assert api.shutdown_requested == "bye"


def test_parameter_updates_go_to_each_subscriber_but_the_setter(api: MasterAPI) -> None:
    api.call("subscribeParam", ("/ns/w", NODE_A, "p"))
    api.call("setParam", ("/ns/w", "/ns/p", 1))
    assert api.outgoing == []  # rosmaster does not tell a node of its own change
    api.call("setParam", ("/other", "/ns/p", 2))
    api.call("deleteParam", ("/other", "/ns/p"))
    assert [(c.uri, c.method, c.args) for c in api.outgoing] == [
        (NODE_A, "paramUpdate", ("/master", "/ns/p/", 2)),
        (NODE_A, "paramUpdate", ("/master", "/ns/p/", {})),
    ]


def test_every_update_a_multicall_makes_is_sent(api: MasterAPI) -> None:
    """The server sends ``outgoing`` once a whole multicall is done: no call may drop it."""
    calls = [
        ("registerSubscriber", ["/s", "/t", "a/B", NODE_B]),
        ("registerPublisher", ["/p", "/t", "a/B", NODE_A]),
        ("registerSubscriber", ["/s2", "/u", "a/B", NODE_C]),
        ("registerPublisher", ["/p2", "/v", "a/B", NODE_C]),
        ("registerService", ["/q", "/srv", "rosrpc://h:1", NODE_C]),
        ("subscribeParam", ["/r", NODE_C, "/k"]),
    ]
    api.call("system.multicall", ([{"methodName": m, "params": p} for m, p in calls],))
    assert [(c.uri, c.method, c.args) for c in api.outgoing] == [
        (NODE_B, "publisherUpdate", ("/master", "/t", [NODE_A])),
    ]


def test_a_nodes_calls_are_cached_under_their_resolved_names(api: MasterAPI) -> None:
    # the server caches the answers to getPublishedTopics and the like
    assert api.cache_key("getPublishedTopics", ("/ns/n", "sub")) == (
        "getPublishedTopics",
        "/ns/sub",
    )


def test_a_value_nested_too_deep_is_refused_as_any_bad_value(api: MasterAPI) -> None:
    deep: Any = 1
    for _ in range(MAX_DEPTH):
        deep = {"a": deep}
    assert api.call("setParam", ("/n", "/deep", deep)) == [
        -1,
        f"ERROR: parameter [/deep] would nest deeper than {MAX_DEPTH} levels",
        0,  # setParam's error value, as rosmaster's
    ]
