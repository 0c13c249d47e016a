"""rostools: the ROS 1 command-line tools in one pip-installable Python CLI, no ROS needed.

It is also a Python API for scripts and tests (``from rostools import Node, publish ...``):
the names in ``__all__`` are the stable API. They load on first use, because every command
of the CLI imports this package and its start-up time counts; ``__init__.pyi`` gives type
checkers their types.
"""

from __future__ import annotations

__version__ = "0.1.0"

#: The private module that defines each public name.
_HOMES = {
    "rostools._api.master": ("Master",),
    "rostools._api.node": ("Node", "Publisher", "Subscription"),
    "rostools._api.asyncnode": ("AsyncNode", "AsyncPublisher", "AsyncSubscription"),
    "rostools._api.functions": (
        "publish",
        "subscribe",
        "wait_for_message",
        "call_service",
        "wait_for_service",
        "get_param",
        "set_param",
        "has_param",
        "delete_param",
    ),
    "rostools._api.messages": ("message", "message_class"),
    "rostools._api.bags": ("record", "Recording", "read_bag", "BagMessage"),
    "rostools._api.snapshots": ("snapshot", "SnapshotRecorder"),
    "rostools.msgs.message": ("Message", "Time", "Duration"),
    "rostools.errors": (
        "RostoolsError",
        "NotFoundError",
        "TimeoutExpired",
        "UnreachableError",
        "UsageError",
        "ServiceError",
    ),
}
_HOME = {name: module for module, names in _HOMES.items() for name in names}

#: The stable API.
__all__ = [
    "AsyncNode",
    "AsyncPublisher",
    "AsyncSubscription",
    "BagMessage",
    "Duration",
    "Master",
    "Message",
    "Node",
    "NotFoundError",
    "Publisher",
    "Recording",
    "RostoolsError",
    "ServiceError",
    "SnapshotRecorder",
    "Subscription",
    "Time",
    "TimeoutExpired",
    "UnreachableError",
    "UsageError",
    "call_service",
    "delete_param",
    "get_param",
    "has_param",
    "message",
    "message_class",
    "publish",
    "read_bag",
    "record",
    "set_param",
    "snapshot",
    "subscribe",
    "wait_for_message",
    "wait_for_service",
]


def __getattr__(name: str) -> object:
    """Load a public name on first use (PEP 562)."""
    home = _HOME.get(name)
    if home is None:
        raise AttributeError(f"module 'rostools' has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(home), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *__all__])
