"""The ROS API argument checks (``wire/rosapi.py``), against what rosmaster and rospy answer.

The master's answers below were captured from a real rosmaster (Noetic, ``rosmaster --core``
on loopback, called with ``xmlrpc.client``); the slave API's messages are rospy's
(``rospy/impl/masterslave.py``, ``rospy/impl/validators.py``).
"""

from __future__ import annotations

from typing import Any

import pytest

from rostools.master.master_api import MasterAPI
from rostools.wire import rosapi

NODE = "http://h:1/"

#: (method, params) -> rosmaster's answer, captured.
ROSMASTER: list[tuple[str, tuple[Any, ...], list[Any]]] = [
    ("registerPublisher", ("/a", "/t:x", "a/B", NODE),
     [-1, "ERROR: parameter [topic] contains illegal chars", []]),
    ("registerPublisher", ("/a", "/t x", "a/B", NODE),
     [-1, "ERROR: parameter [topic] contains illegal chars", []]),
    ("registerPublisher", ("/a", "/", "a/B", NODE),
     [-1, "ERROR: parameter [topic] cannot be the global namespace", []]),
    ("registerPublisher", ("/a", "", "a/B", NODE),
     [-1, "ERROR: parameter [topic] must be a non-empty string", []]),
    ("registerPublisher", ("/a", "/t", "", NODE),
     [-1, "ERROR: parameter [topic_type] must be a non-empty string", []]),
    ("registerPublisher", ("/a", "/t", 5, NODE),
     [-1, "ERROR: parameter [topic_type] must be a non-empty string", []]),
    ("registerPublisher", ("/a", "/t", "a/B/C", NODE),
     [-1, "ERROR: parameter [topic_type] is not a valid package resource name", []]),
    ("registerPublisher", ("/a", "/t", "a/B", ""),
     [-1, "ERROR: parameter [caller_api] is not an XMLRPC URI", []]),
    ("registerPublisher", ("/a", "/t", "a/B", 7),
     [-1, "ERROR: parameter [caller_api] is not an XMLRPC URI", []]),
    ("registerPublisher", ("/a", "/t", "a/B", "ftp://h"),
     [-1, "ERROR: parameter [caller_api] is not an RPC URI", []]),
    ("registerService", ("/a", "/s", "", NODE),
     [-1, "ERROR: parameter [service_api] is not an XMLRPC URI", 0]),
    ("lookupNode", ("/a", "no:de"), [-1, "ERROR: parameter [node] contains illegal chars", ""]),
    ("lookupNode", ("/a", ""), [-1, "ERROR: parameter [node] must be a non-empty string", ""]),
    ("lookupNode", ("/ns/a", "rel"), [-1, "unknown node [/ns/rel]", ""]),
    ("lookupService", ("/a", "/"),
     [-1, "ERROR: parameter [service] cannot be the global namespace", ""]),
    ("getPublishedTopics", ("/a", 5), [-1, "ERROR: parameter [subgraph] must be a string", 0]),
    ("setParam", ("/a", "/p", None), [-1, "ERROR: parameter [value] must be specified", 0]),
    ("setParam", ("/a", "", 1), [-1, "ERROR: parameter [key] must be specified and non-empty", 0]),
    ("setParam", ("/a", 5, 1), [-1, "ERROR: parameter [key] must be a string", 0]),
    ("getParam", ("/a", ""), [-1, "ERROR: parameter [key] must be specified and non-empty", 0]),
    ("getParam", ("/a", 3), [-1, "ERROR: parameter [key] must be a string", 0]),
    ("hasParam", ("/a", ""),
     [-1, "ERROR: parameter [key] must be specified and non-empty", False]),
    ("searchParam", ("/a", ""), [-1, "ERROR: parameter [key] must be specified and non-empty", 0]),
    ("deleteParam", ("/a", ""), [-1, "ERROR: parameter [key] must be specified and non-empty", 0]),
    ("subscribeParam", ("/a", "bad", "/p"),
     [-1, "ERROR: parameter [caller_api] is not an RPC URI", 0]),
    ("getPid", ("/a", 1), [-1, "Error: bad call arity", -1]),
    ("getPid", (), [-1, "missing required caller_id parameter", -1]),
    ("getPid", (5,), [-1, "caller_id must be a string", -1]),
]  # fmt: skip


@pytest.mark.parametrize(("method", "params", "answer"), ROSMASTER)
def test_bad_arguments_get_rosmasters_answer(
    method: str, params: tuple[Any, ...], answer: list[Any]
) -> None:
    assert MasterAPI("http://localhost:11311/", pid=42).call(method, params) == answer


#: getPublishedTopics(caller, subgraph) -> rosmaster's topics, captured with publishers of
#: /a/x, /ab/x, /ns/a/y and /ns/ab: a relative subgraph is the caller's namespace's, and a
#: subgraph matches whole names only (/a is not a prefix of /ab/x).
PUBLISHED = [
    ("/ns/node", "a", ["/ns/a/y"]),
    ("/ns/node", "", ["/a/x", "/ab/x", "/ns/a/y", "/ns/ab"]),
    ("/x", "/a", ["/a/x"]),
    ("/x", "/", ["/a/x", "/ab/x", "/ns/a/y", "/ns/ab"]),
    ("/x", "/a/", ["/a/x"]),
    ("/ns/node", "/ns", ["/ns/a/y", "/ns/ab"]),
    ("/ns/node", "~p", []),
]


@pytest.mark.parametrize(("caller", "subgraph", "topics"), PUBLISHED)
def test_published_topics_under_a_subgraph_as_rosmaster(
    caller: str, subgraph: str, topics: list[str]
) -> None:
    api = MasterAPI("http://localhost:11311/", pid=42)
    for topic in ("/a/x", "/ab/x", "/ns/a/y", "/ns/ab"):
        assert api.call("registerPublisher", ("/pub", topic, "std_msgs/Empty", NODE))[0] == 1
    code, message, found = api.call("getPublishedTopics", (caller, subgraph))
    assert (code, message) == (1, "current topics")
    assert sorted(found) == [[t, "std_msgs/Empty"] for t in topics]


@pytest.mark.parametrize(
    ("factory", "name", "value", "message"),
    [
        ("uri_list", "publishers", "http://a:1/", "ERROR: param [publishers] must be a list"),
        ("uri_list", "publishers", [5], "ERROR: param [publishers] must be a list of strings"),
        ("uri_list", "publishers", ["a:1"],
         "ERROR: param [publishers] does not contain valid URLs [a:1]"),
        ("uri_list", "publishers", ["http://"],
         "ERROR: param [publishers] does not contain valid URLs [http://]"),
        ("non_empty", "topic", "", "ERROR: parameter [topic] must be specified and non-empty"),
        ("global_name", "parameter_key", "rel",
         "ERROR: parameter [parameter_key] must be a globally referenced name"),
        ("global_name", "parameter_key", "",
         "ERROR: parameter [parameter_key] must be a non-empty string"),
    ],
)  # fmt: skip
def test_slave_api_checks_say_what_rospy_says(
    factory: str, name: str, value: Any, message: str
) -> None:
    check = getattr(rosapi, factory)(name)  # made in the test: a check is a closure
    with pytest.raises(rosapi.ArgumentError) as caught:
        check(value, "/caller")
    assert str(caught.value) == message


def test_slave_api_checks_pass_good_values_through() -> None:
    uris = ["http://a:1/", "rosrpc://b:2"]
    assert rosapi.uri_list("publishers")(uris, "/c") == uris
    assert rosapi.uri_list("publishers")([], "/c") == []
    assert rosapi.non_empty("topic")("/t", "/c") == "/t"
    assert rosapi.global_name("parameter_key")("/p/", "/c") == "/p/"


def test_a_cached_answer_is_kept_under_the_resolved_call() -> None:
    methods = MasterAPI("http://localhost:11311/", pid=42).methods
    # A relative name means another topic to a caller in another namespace (ROS name rules).
    first = rosapi.cache_key(methods, "lookupService", ("/ns1/n", "s"))
    second = rosapi.cache_key(methods, "lookupService", ("/ns2/n", "s"))
    assert first == ("lookupService", "/ns1/s")
    assert second == ("lookupService", "/ns2/s")
    # The caller itself is not part of the key: the same resolved call, the same answer.
    assert rosapi.cache_key(methods, "lookupService", ("/ns1/m", "/ns1/s")) == first
    assert rosapi.cache_key(methods, "nope", ("/a",)) is None
    assert rosapi.cache_key(methods, "lookupService", ("/a",)) is None  # bad arity
    assert rosapi.cache_key(methods, "setParam", ("/a", "/p", [1])) is None  # unhashable
    assert rosapi.cache_key(methods, "getParam", ("/a", "/p")) == ("getParam", "/p")


def test_a_handler_that_fails_is_answered_in_words_not_pythons(
    caplog: pytest.LogCaptureFixture,
) -> None:
    """A handler's own failure keeps its words (rosmaster's "Internal failure: invalid key");
    any other error is ours, and the caller learns the method and its kind, not Python's text
    ("unpack_from requires a buffer of at least 1 bytes"), which goes to the log, one line."""
    import struct

    def unpack(caller: str) -> rosapi.Triple:
        struct.unpack_from("<I", b"")
        raise AssertionError("unreachable")

    def refuse(caller: str) -> rosapi.Triple:
        raise rosapi.Failure("invalid key")

    methods = {"unpack": (unpack, 0, ()), "refuse": (refuse, "", ())}
    assert rosapi.dispatch(methods, "refuse", ("/c",)) == [0, "Internal failure: invalid key", ""]
    answer = rosapi.dispatch(methods, "unpack", ("/c",))
    assert answer == [0, "Internal failure: unpack failed (struct.error)", 0]
    [record] = caplog.records
    assert record.getMessage().startswith("unpack failed: struct.error: unpack_from requires")
