"""The parameter tree and its update notifications (wiki.ros.org/ROS/Parameter Server)."""

from __future__ import annotations

import pytest

from rostools.master.params import ParamTree, subscription_key


def test_dict_replaces_subtree_and_set_below_scalar() -> None:
    tree = ParamTree()
    tree.set("/cfg", {"x": 1, "y": 2.5, "sub": {"z": "s"}})
    tree.set("/cfg", {"x": 10})
    assert tree.get("/cfg") == {"x": 10}
    tree.set("/sc", 1)
    tree.set("/sc/child", 2)
    assert tree.get("/sc") == {"child": 2}
    assert sorted(tree.names()) == ["/cfg/x", "/sc/child"]


def test_root_and_missing_keys() -> None:
    tree = ParamTree()
    with pytest.raises(TypeError, match="cannot set root"):
        tree.set("/", 5)
    tree.set("/", {"a": {}})
    assert tree.has("/a") and tree.names() == []
    with pytest.raises(KeyError):
        tree.delete("/")
    with pytest.raises(KeyError):
        tree.get("/a/b")
    with pytest.raises(KeyError):
        tree.delete("/nope/x")


def test_search_walks_up_from_the_caller() -> None:
    tree = ParamTree()
    tree.set("/ns1/rel", 1)
    tree.set("/robot_description", "urdf")
    assert tree.search("/ns1/sub/node", "rel") == "/ns1/rel"
    assert tree.search("/ns1/node", "rel/deeper") == "/ns1/rel/deeper"
    assert tree.search("/ns1/node", "robot_description") == "/robot_description"
    assert tree.search("/ns1/node", "/robot_description") == "/robot_description"
    assert tree.search("/ns1/node", "nothing") is None
    with pytest.raises(ValueError, match="invalid key"):
        tree.search("/n", "~private")


def test_update_sequence_observed_on_rosmaster() -> None:
    subs = {
        subscription_key("/cfg"): [("/a", "http://a:1/")],
        subscription_key("/cfg/sub/z"): [("/b", "http://b:1/")],
    }
    tree = ParamTree(subs)
    first = tree.set("/cfg", {"x": 1, "y": 2.5, "sub": {"z": "s"}}, caller_id="/setter")
    assert [(k, v) for _, _, k, v in first] == [
        ("/cfg/", {"x": 1, "y": 2.5, "sub": {"z": "s"}}),
        ("/cfg/sub/z/", "s"),
    ]
    second = tree.set("/cfg", {"x": 10}, caller_id="/setter")
    assert [(k, v) for _, _, k, v in second] == [("/cfg/", {"x": 10}), ("/cfg/sub/z/", {})]
    third = tree.delete("/cfg/x")
    assert [(k, v) for _, _, k, v in third] == [("/cfg/x/", {})]


def test_setter_is_not_told_of_its_own_change() -> None:
    tree = ParamTree({"/p/": [("/me", "http://me:1/"), ("/you", "http://you:1/")]})
    updates = tree.set("/p", 3, caller_id="/me")
    assert [cid for cid, _, _, _ in updates] == ["/you"]
