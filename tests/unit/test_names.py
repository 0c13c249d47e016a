"""Graph resource names."""

from __future__ import annotations

import pytest

from rostools import names


@pytest.mark.parametrize(
    ("name", "canonical"),
    [("//a//b/", "/a/b"), ("/", "/"), ("a/b/", "a/b"), ("", "")],
)
def test_canonicalize(name: str, canonical: str) -> None:
    assert names.canonicalize(name) == canonical


@pytest.mark.parametrize(
    ("name", "caller", "resolved"),
    [
        ("/x", "/ns/node", "/x"),
        ("x", "/ns/node", "/ns/x"),
        ("~x", "/ns/node", "/ns/node/x"),
        ("", "/ns/node", "/ns/"),
        ("rel", "/ns1/node", "/ns1/rel"),
        ("a//b/", "/node", "/a/b"),
    ],
)
def test_resolve(name: str, caller: str, resolved: str) -> None:
    assert names.resolve(name, caller) == resolved


def test_resolve_applies_remappings_after_resolution() -> None:
    assert names.resolve("chatter", "/ns/n", {"/ns/chatter": "/other"}) == "/other"


def test_namespace_and_join() -> None:
    assert names.namespace("/wg/node1") == "/wg/"
    assert names.namespace("/node") == "/"
    assert names.join("/a", "b") == "/a/b"
    assert names.join("/a/", "/b") == "/b"
    assert names.make_global_ns("a") == "/a/"


def test_script_resolve_uses_ros_namespace() -> None:
    env = {"ROS_NAMESPACE": "/robot"}
    assert names.script_resolve("chatter", env=env) == "/robot/chatter"
    assert names.script_resolve("/chatter", env=env) == "/chatter"
    assert names.script_resolve("~p", "rosparam", env=env) == "/robot/rosparam/p"
    assert names.script_resolve("", env=env) == "/robot/"
    assert names.script_resolve("x", env={}) == "/x"


def test_split_remappings() -> None:
    rest, mapping = names.split_remappings(["/t", "__name:=n", "a:=b", "_p:=1", "x:y"])
    assert rest == ["/t", "x:y"]
    assert mapping == {"__name": "n", "a": "b", "_p": "1"}


def test_legal_names() -> None:
    assert names.is_legal("/a/b_1") and names.is_legal("~p") and not names.is_legal("1a")
    assert not names.is_legal("/a//b") and names.is_legal_base("node_1")
