"""The module-level functions (``rostools.publish``, ``get_param`` ...), on a default node.

As in rospy, a script need not make a node: the first call starts one named
``/rostools_api_...`` on ``ROS_MASTER_URI``. When ``ROS_MASTER_URI`` changes (a test
fixture points it at a new master), the next call starts a new node there.
"""

from __future__ import annotations

import threading
from typing import Any

from rostools._api.asyncnode import AsyncNode, Callback, default_master_uri
from rostools._api.blocking import Node, Subscription
from rostools._api.messages import Values
from rostools.msgs.message import Message
from rostools.rosgraph.masterapi import SERVICE_TIMEOUT

_lock = threading.Lock()
_nodes: dict[str, Node] = {}


def default_node() -> Node:
    """The node the functions use, on the current ``ROS_MASTER_URI``."""
    uri = default_master_uri()
    with _lock:
        node = _nodes.get(uri)
        if node is None or node.closed:
            node = _nodes[uri] = Node("rostools_api", uri)
        return node


def reset() -> None:
    """Close every default node (a test's master is going away)."""
    with _lock:
        nodes = list(_nodes.values())
        _nodes.clear()
    for node in nodes:
        node.close()


def default_nodes() -> list[Node]:
    """The default nodes running now."""
    with _lock:
        return [n for n in _nodes.values() if not n.closed]


def publish(topic: str, msg: Values, msg_type: str | None = None) -> None:
    """Publish one message, latched, so a subscriber that connects later still gets it."""
    default_node().publish(topic, msg, msg_type)


def subscribe(
    topic: str, callback: Callback | None = None, msg_type: str | None = None
) -> Subscription:
    """Receive ``topic``: with ``callback`` (on a thread of its own), or iterate the result."""
    return default_node().subscribe(topic, callback, msg_type)


def wait_for_message(
    topic: str, timeout: float | None = None, msg_type: str | None = None
) -> Message:
    """The next message on ``topic``; ``TimeoutExpired`` after ``timeout`` seconds."""
    return default_node().wait_for_message(topic, timeout, msg_type)


def call_service(
    service: str,
    request: Values = None,
    srv_type: str | None = None,
    *,
    timeout: float = SERVICE_TIMEOUT,
    **fields: Any,
) -> Message:
    """Call ``service`` with a request (message, dict, YAML or keywords); the response."""
    return default_node().call_service(service, request, srv_type, timeout=timeout, **fields)


def wait_for_service(service: str, timeout: float | None = None) -> None:
    """Until the master knows ``service``."""
    default_node().wait_for_service(service, timeout)


def get_param(key: str, default: Any = AsyncNode._MISSING) -> Any:
    """A parameter's value; ``default`` when unset, else ``NotFoundError``."""
    return default_node().get_param(key, default)


def set_param(key: str, value: Any) -> None:
    """Set a parameter (a dict sets a tree)."""
    default_node().set_param(key, value)


def has_param(key: str) -> bool:
    """Whether a parameter is set."""
    return default_node().has_param(key)


def delete_param(key: str) -> None:
    """Delete a parameter; ``NotFoundError`` when unset."""
    default_node().delete_param(key)
