"""An action client on the live node: send goals, follow their status and feedback, cancel.

``wait_for_server`` waits, as actionlib's ``waitForServer`` does, until the server is
connected on every topic: a goal sent earlier could be lost, and a result missed. While goals
are open, the client watches its connections to the server: when they are all gone for
``LOST_AFTER`` seconds, the open goals end as LOST rather than waiting forever.
"""

from __future__ import annotations

import asyncio
import contextlib
import time
from typing import TYPE_CHECKING, Any, NamedTuple

from rostools.action import status as st
from rostools.action.goalid import goal_id
from rostools.action.types import ActionTypes
from rostools.errors import TimeoutExpired
from rostools.msgs.message import Time
from rostools.msgs.topictype import TopicType

if TYPE_CHECKING:
    from rostools.node.connection import Frame, InboundConnection
    from rostools.node.node import LiveNode
    from rostools.node.publisher import TopicPublisher
    from rostools.node.subscriber import Subscriber

#: How long the server may be out of reach on every topic before open goals are LOST (s).
LOST_AFTER = 0.5
#: How often the client checks on the server while goals are open (s).
WATCH_PERIOD = 0.1


class GoalEvent(NamedTuple):
    """Something that happened to a goal: ``kind`` is status, feedback, result or lost."""

    kind: str
    goal_id: str
    status: int
    text: str
    #: The feedback or result message (None for status and lost).
    message: Any = None


class ClientGoalHandle:
    """One goal sent: its latest status, its events in order, its end."""

    def __init__(self, client: ActionClient, gid: str, stamp: Time) -> None:
        self.client = client
        self.id = gid
        self.stamp = stamp
        #: Latest status; -1 until the server first lists the goal.
        self.status = -1
        self.text = ""
        self.events: asyncio.Queue[GoalEvent] = asyncio.Queue()
        self.done: asyncio.Future[GoalEvent] = asyncio.get_running_loop().create_future()

    def _event(self, event: GoalEvent) -> None:
        if self.done.done():
            return
        if event.kind != "feedback":
            self.status, self.text = event.status, event.text
        self.events.put_nowait(event)
        if event.kind in ("result", "lost"):
            self.done.set_result(event)

    def update(self, code: int, text: str) -> None:
        """A status array listed this goal."""
        if code != self.status and not self.done.done():
            self._event(GoalEvent("status", self.id, code, text))

    def cancel(self) -> None:
        """Ask the server to cancel this goal."""
        self.client.cancel(self.id)

    async def result(self, timeout: float | None = None) -> GoalEvent:
        """The goal's last event (result or lost); ``TimeoutExpired`` after ``timeout``."""
        try:
            return await asyncio.wait_for(asyncio.shield(self.done), timeout)
        except asyncio.TimeoutError:
            raise TimeoutExpired(f"goal {self.id} did not finish within {timeout:g} s") from None


class ActionClient:
    """A client of the action ``name`` (``/fib``) with the types in ``types``."""

    def __init__(self, node: LiveNode, name: str, types: ActionTypes) -> None:
        self.node = node
        self.name = node.resolve(name)
        self.types = types
        self.goals: dict[str, ClientGoalHandle] = {}
        #: The latest status array: goal id -> (status, text, stamp in ns).
        self.statuses: dict[str, tuple[int, str, int]] = {}
        #: Set on each status array.
        self.status_received = asyncio.Event()
        self._goal_pub: TopicPublisher | None = None
        self._cancel_pub: TopicPublisher | None = None
        self._subs: dict[str, Subscriber] = {}
        self._watch: asyncio.Task[None] | None = None
        self._unreached_since: float | None = None

    def topic(self, part: str) -> str:
        """``/fib/goal`` and the like."""
        return f"{self.name}/{part}"

    async def start(self, *, goals: bool = True, cancel: bool = True) -> ActionClient:
        """Register: status always; the goal side and the cancel publisher as asked."""
        types = self.types
        if goals:
            goal_type = types.topic_type("ActionGoal")
            self._goal_pub = await self.node.advertise(self.topic("goal"), goal_type)
            if goal_type.md5sum == "*":
                self._goal_pub.on_subscriber = self._learn_goal
            for part, suffix, handler in (
                ("feedback", "ActionFeedback", self._on_feedback),
                ("result", "ActionResult", self._on_result),
            ):
                self._subs[part] = await self.node.subscribe(
                    self.topic(part), self._frames(handler), types.topic_type(suffix),
                    on_header=self._learn_header,
                )  # fmt: skip
        if cancel or goals:
            self._cancel_pub = await self.node.advertise(
                self.topic("cancel"), types.wire(st.GOAL_ID)
            )
        self._subs["status"] = await self.node.subscribe(
            self.topic("status"), self._frames(self._on_status), types.wire(st.STATUS_ARRAY)
        )
        self._watch = asyncio.get_running_loop().create_task(self._watch_server())
        return self

    # the server ---------------------------------------------------------------------------

    def server_connected(self) -> bool:
        """Whether the server is connected on every topic this client uses."""
        for pub in (self._goal_pub, self._cancel_pub):
            if pub is not None and (pub.subscriber_count == 0 or pub.type.md5sum == "*"):
                return False
        for sub in self._subs.values():
            if not any(c.header is not None for c in sub.connections.values()):
                return False
        return self.status_received.is_set()

    async def wait_for_server(self, timeout: float | None) -> None:
        """Wait until ``server_connected``; ``TimeoutExpired`` after ``timeout`` seconds."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while not self.server_connected():
            if deadline is not None and time.monotonic() >= deadline:
                raise TimeoutExpired(
                    f"the action server of {self.name} did not connect within {timeout:g} s",
                    hint="is its node running, and can it reach this host? "
                    "(rostools action info " + self.name + ")",
                )
            await asyncio.sleep(0.02)

    def _reached(self) -> bool:
        return any(
            c.header is not None for sub in self._subs.values() for c in sub.connections.values()
        )

    async def _watch_server(self) -> None:
        while True:
            await asyncio.sleep(WATCH_PERIOD)
            open_goals = [g for g in self.goals.values() if not g.done.done()]
            if self._reached() or not open_goals:
                self._unreached_since = None
                continue
            now = time.monotonic()
            self._unreached_since = self._unreached_since or now
            if now - self._unreached_since >= LOST_AFTER:
                for handle in open_goals:
                    text = f"the action server of {self.name} went away"
                    handle._event(GoalEvent("lost", handle.id, st.LOST, text))

    # goals --------------------------------------------------------------------------------

    def send_goal(self, goal: Any) -> ClientGoalHandle:
        """Publish ``goal`` (a ``<stem>Goal`` message) under a new goal id."""
        assert self._goal_pub is not None, "start(goals=True) first"
        gid, stamp = goal_id(self.node.name)
        handle = self.goals[gid] = ClientGoalHandle(self, gid, stamp)
        message = self.types.message(
            "ActionGoal",
            header=self.types.header(),
            goal_id=self.types.goal_id(gid, stamp),
            goal=goal,
        )
        self._goal_pub.publish(message.serialize())
        self._goal_pub.flush()
        return handle

    def cancel(self, gid: str = "", stamp: Time | None = None) -> None:
        """Publish a cancel request: one goal, or (no id, no stamp) every goal."""
        assert self._cancel_pub is not None, "start(cancel=True) first"
        self._cancel_pub.publish(self.types.goal_id(gid, stamp).serialize())
        self._cancel_pub.flush()

    def cancel_subscribers(self) -> int:
        """How many servers listen to our cancel requests."""
        return 0 if self._cancel_pub is None else self._cancel_pub.subscriber_count

    # incoming -----------------------------------------------------------------------------

    def _learn_goal(self, fields: dict[str, str]) -> None:
        """The server's goal subscriber told us its type: take it as ours."""
        assert self._goal_pub is not None
        learnt = TopicType.from_header(fields)
        if learnt.md5sum != "*" and learnt.type == self._goal_pub.type.type:
            self.types.learn(learnt)
            self._goal_pub.type = learnt._replace(has_header=True)
            self._goal_pub.on_subscriber = None

    def _learn_header(self, conn: InboundConnection) -> None:
        if conn.header is not None:
            self.types.learn(TopicType.from_header(conn.header))

    def _frames(self, handler: Any) -> Any:
        def received(frames: list[Frame], conn: InboundConnection, now: float) -> None:
            for frame in frames:
                handler(bytes(frame))

        return received

    def _on_status(self, data: bytes) -> None:
        array = self.types.codec.decode(st.STATUS_ARRAY, data)
        self.statuses = {
            s.goal_id.id: (s.status, s.text, s.goal_id.stamp.to_nsec()) for s in array.status_list
        }
        for gid, (code, text, _) in self.statuses.items():
            handle = self.goals.get(gid)
            if handle is not None:
                handle.update(code, text)
        self.status_received.set()

    def _on_feedback(self, data: bytes) -> None:
        if not self.types.known("ActionFeedback"):
            return
        message = self.types.decode("ActionFeedback", data)
        handle = self.goals.get(message.status.goal_id.id)
        if handle is not None:
            handle.update(message.status.status, message.status.text)
            event = GoalEvent(
                "feedback", handle.id, message.status.status, message.status.text,
                message.feedback,
            )  # fmt: skip
            handle._event(event)

    def _on_result(self, data: bytes) -> None:
        if not self.types.known("ActionResult"):
            return
        message = self.types.decode("ActionResult", data)
        handle = self.goals.get(message.status.goal_id.id)
        if handle is not None:
            code, text = message.status.status, message.status.text
            handle.update(code, text)
            handle._event(GoalEvent("result", handle.id, code, text, message.result))

    async def close(self) -> None:
        """Stop watching (the node unregisters the topics when it closes)."""
        if self._watch is not None:
            self._watch.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._watch
