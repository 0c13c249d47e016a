"""The types of one action: its seven messages, and the store and codec that resolve them.

They come from the store (the built-in table, ``.action`` files on the search path) when it
has them, and otherwise from the peers: the server's publishers send the definitions of the
result and feedback in their connection headers, and its goal subscriber sends the goal's.
"""

from __future__ import annotations

from typing import Any

from rostools.action.status import GOAL_ID, STATUS, STATUS_ARRAY
from rostools.msgs.action import action_name
from rostools.msgs.codec import Codec
from rostools.msgs.message import Time
from rostools.msgs.store import TypeStore
from rostools.msgs.topictype import TopicType


class ActionTypes:
    """The types of the action ``pkg/NameAction``, as far as they are known."""

    def __init__(self, store: TypeStore, name: str) -> None:
        self.name = action_name(name)
        self.stem = self.name.removesuffix("Action")
        self.store = store
        self.codec = Codec.of(store)

    def known(self, suffix: str) -> bool:
        """Whether the message ``<stem><suffix>`` (``ActionGoal``, ...) resolves."""
        return self.store.has_msg(self.stem + suffix)

    def topic_type(self, suffix: str) -> TopicType:
        """The TCPROS type of ``ActionGoal``, ``ActionResult`` or ``ActionFeedback``.

        An unknown one is the name with md5sum ``*``, to be learnt from the first peer.
        """
        if self.known(suffix):
            return TopicType.of(self.store, self.stem + suffix)
        return TopicType(self.stem + suffix, "*", "", True)

    def learn(self, topic_type: TopicType) -> None:
        """Take a definition a peer sent, if the store lacks the type."""
        if topic_type.md5sum == "*" or self.store.has_msg(topic_type.type):
            return
        self.store = self.store.with_definition(topic_type.type, topic_type.definition)
        self.codec = Codec.of(self.store)

    def message(self, suffix: str, **fields: Any) -> Any:
        """A new message ``<stem><suffix>`` (``Goal``, ``Result``, ...) with these fields."""
        return self.codec.message_class(self.stem + suffix)(**fields)

    def decode(self, suffix: str, data: Any) -> Any:
        """Decode a message of ``<stem><suffix>``."""
        return self.codec.decode(self.stem + suffix, data)

    # actionlib_msgs ---------------------------------------------------------------------

    def goal_id(self, goal_id: str = "", stamp: Time | None = None) -> Any:
        """An actionlib_msgs/GoalID."""
        return self.codec.message_class(GOAL_ID)(stamp=stamp or Time(), id=goal_id)

    def status(self, goal_id: str, stamp: Time, code: int, text: str = "") -> Any:
        """An actionlib_msgs/GoalStatus."""
        cls = self.codec.message_class(STATUS)
        return cls(goal_id=self.goal_id(goal_id, stamp), status=code, text=text)

    def status_array(self, statuses: list[Any]) -> Any:
        """An actionlib_msgs/GoalStatusArray stamped now."""
        cls = self.codec.message_class(STATUS_ARRAY)
        return cls(header=self.header(), status_list=statuses)

    def header(self) -> Any:
        """A std_msgs/Header stamped now (the publisher sets ``seq``)."""
        return self.codec.message_class("std_msgs/Header")(stamp=Time.now())

    def wire(self, type_name: str) -> TopicType:
        """The TCPROS type of an actionlib_msgs type (always in the store)."""
        return TopicType.of(self.store, type_name)
