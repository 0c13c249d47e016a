"""Types of the public API for type checkers (the names load lazily at run time)."""

from rostools._api.asyncnode import AsyncNode, AsyncPublisher, AsyncSubscription
from rostools._api.bags import BagMessage, Recording, read_bag, record
from rostools._api.functions import (
    call_service,
    delete_param,
    get_param,
    has_param,
    publish,
    set_param,
    subscribe,
    wait_for_message,
    wait_for_service,
)
from rostools._api.master import Master
from rostools._api.messages import message, message_class
from rostools._api.node import Node, Publisher, Subscription
from rostools._api.snapshots import SnapshotRecorder, snapshot
from rostools.errors import (
    NotFoundError,
    RostoolsError,
    ServiceError,
    TimeoutExpired,
    UnreachableError,
    UsageError,
)
from rostools.msgs.message import Duration, Message, Time

__version__: str
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
