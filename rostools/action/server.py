"""An action server on the live node: goals in, status, feedback and results out.

Each goal runs ``execute(handle)`` in its own task. With ``auto_accept`` (the default, as
actionlib's SimpleActionServer) the goal is ACTIVE when ``execute`` starts; otherwise it is
PENDING and ``execute`` calls ``accept()`` or ``reject()``. When ``execute`` returns without
ending the goal, what it returned is the result: SUCCEEDED, or PREEMPTED/RECALLED when a
cancel was asked for. An exception ABORTs the goal (REJECTs it while PENDING), with its text.

The status array goes out at ``status_rate`` Hz and on every change, as actionlib's servers
send it; goals that ended stay listed for ``KEEP_DONE`` seconds.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections.abc import Awaitable, Callable
from typing import TYPE_CHECKING, Any

from rostools.action import status as st
from rostools.action.types import ActionTypes
from rostools.msgs.message import Time

if TYPE_CHECKING:
    from rostools.node.connection import Frame, InboundConnection
    from rostools.node.node import LiveNode
    from rostools.node.publisher import TopicPublisher

log = logging.getLogger(__name__)

#: How long a goal that ended stays in the status array (actionlib's status_list_timeout).
KEEP_DONE = 5.0
#: actionlib's default status_frequency (Hz).
STATUS_RATE = 5.0

Execute = Callable[["ServerGoalHandle"], Awaitable[Any]]


class ServerGoalHandle:
    """One goal the server received."""

    def __init__(self, server: ActionServer, gid: str, stamp: Time, goal: Any) -> None:
        self.server = server
        self.id = gid
        self.stamp = stamp
        #: The ``<stem>Goal`` message.
        self.goal = goal
        self.status = st.PENDING
        self.text = ""
        #: Set when a cancel request covers this goal.
        self.cancel_requested = asyncio.Event()
        self.ended_at: float | None = None

    @property
    def done(self) -> bool:
        """Whether the goal has ended (its result is out)."""
        return self.status in st.TERMINAL

    def _set(self, code: int, text: str | None = None) -> None:
        self.status = code
        if text is not None:
            self.text = text
        self.server.publish_status()

    def accept(self, text: str = "") -> None:
        """PENDING -> ACTIVE (RECALLING -> PREEMPTING: the cancel still stands)."""
        if self.status == st.PENDING:
            self._set(st.ACTIVE, text)
        elif self.status == st.RECALLING:
            self._set(st.PREEMPTING, text)

    def reject(self, text: str = "", result: Any = None) -> None:
        """Refuse a PENDING goal."""
        if self.status in (st.PENDING, st.RECALLING):
            self._end(st.REJECTED, text, result)

    def publish_feedback(self, feedback: Any = None, /, **fields: Any) -> None:
        """Send a ``<stem>Feedback``: the message, or its fields by name."""
        if self.done:
            return
        types = self.server.types
        message = types.message(
            "ActionFeedback",
            header=types.header(),
            status=types.status(self.id, self.stamp, self.status, self.text),
            feedback=feedback if feedback is not None else types.message("Feedback", **fields),
        )
        self.server.publish("feedback", message)

    def succeed(self, result: Any = None, text: str = "") -> None:
        """End an ACTIVE (or PREEMPTING) goal as SUCCEEDED."""
        if self.status in (st.ACTIVE, st.PREEMPTING):
            self._end(st.SUCCEEDED, text, result)

    def abort(self, result: Any = None, text: str = "") -> None:
        """End an ACTIVE (or PREEMPTING) goal as ABORTED."""
        if self.status in (st.ACTIVE, st.PREEMPTING):
            self._end(st.ABORTED, text, result)

    def canceled(self, result: Any = None, text: str = "") -> None:
        """End the goal because of a cancel: PREEMPTED once active, RECALLED before."""
        if self.status in (st.PENDING, st.RECALLING):
            self._end(st.RECALLED, text, result)
        elif self.status in (st.ACTIVE, st.PREEMPTING):
            self._end(st.PREEMPTED, text, result)

    def _request_cancel(self) -> None:
        if self.status == st.PENDING:
            self._set(st.RECALLING)
        elif self.status == st.ACTIVE:
            self._set(st.PREEMPTING)
        if not self.done:
            self.cancel_requested.set()

    def _end(self, code: int, text: str, result: Any) -> None:
        types = self.server.types
        self.status, self.text = code, text
        self.ended_at = time.monotonic()
        message = types.message(
            "ActionResult",
            header=types.header(),
            status=types.status(self.id, self.stamp, code, text),
            result=result if result is not None else types.message("Result"),
        )
        self.server.publish("result", message)
        self.server.publish_status()


class ActionServer:
    """A server of the action ``name`` (``/fib``) of type ``types``."""

    def __init__(
        self,
        node: LiveNode,
        name: str,
        types: ActionTypes,
        execute: Execute,
        *,
        auto_accept: bool = True,
        status_rate: float = STATUS_RATE,
    ) -> None:
        self.node = node
        self.name = node.resolve(name)
        self.types = types
        self.execute = execute
        self.auto_accept = auto_accept
        self.status_rate = status_rate
        self.goals: dict[str, ServerGoalHandle] = {}
        self.tasks: set[asyncio.Task[None]] = set()
        self._pubs: dict[str, TopicPublisher] = {}
        self._timer: asyncio.Task[None] | None = None
        self._last_cancel_ns = 0

    async def start(self) -> ActionServer:
        """Advertise status, feedback and result; subscribe to goals and cancels."""
        types = self.types
        self._pubs["status"] = await self.node.advertise(
            f"{self.name}/status", types.wire(st.STATUS_ARRAY)
        )
        for part, suffix in (("feedback", "ActionFeedback"), ("result", "ActionResult")):
            self._pubs[part] = await self.node.advertise(
                f"{self.name}/{part}", types.topic_type(suffix)
            )
        await self.node.subscribe(
            f"{self.name}/goal", self._frames(self._on_goal), types.topic_type("ActionGoal")
        )
        await self.node.subscribe(
            f"{self.name}/cancel", self._frames(self._on_cancel), types.wire(st.GOAL_ID)
        )
        self._timer = asyncio.get_running_loop().create_task(self._publish_status_forever())
        return self

    def publish(self, part: str, message: Any) -> None:
        """Send a message on ``status``, ``feedback`` or ``result``."""
        pub = self._pubs.get(part)
        if pub is not None:
            pub.publish(message.serialize())

    def publish_status(self) -> None:
        """Send the status array now; goals ended long enough ago leave it."""
        now = time.monotonic()
        for gid, handle in list(self.goals.items()):
            if handle.ended_at is not None and now - handle.ended_at > KEEP_DONE:
                del self.goals[gid]
        types = self.types
        statuses = [types.status(h.id, h.stamp, h.status, h.text) for h in self.goals.values()]
        self.publish("status", types.status_array(statuses))

    async def _publish_status_forever(self) -> None:
        period = 1.0 / self.status_rate if self.status_rate > 0 else None
        while period is not None:
            self.publish_status()
            await asyncio.sleep(period)

    def _frames(self, handler: Any) -> Any:
        def received(frames: list[Frame], conn: InboundConnection, now: float) -> None:
            for frame in frames:
                try:
                    handler(bytes(frame))
                except Exception as err:  # noqa: BLE001 - one bad message must not stop the server
                    log.warning("%s: dropped a message that does not decode: %s", self.name, err)

        return received

    def _on_goal(self, data: bytes) -> None:
        message = self.types.decode("ActionGoal", data)
        gid, stamp = message.goal_id.id, message.goal_id.stamp
        if stamp.is_zero():
            stamp = Time.now()
        if not gid:
            gid = f"{self.node.name}-goal-{stamp.secs}.{stamp.nsecs}"
        known = self.goals.get(gid)
        if known is not None:  # a repeat: actionlib ignores it, unless it was being recalled
            if known.status == st.RECALLING:
                known.canceled()
            return
        handle = self.goals[gid] = ServerGoalHandle(self, gid, stamp, message.goal)
        if self._last_cancel_ns and stamp.to_nsec() <= self._last_cancel_ns:
            handle.canceled(text="canceled before it arrived")
            return
        if self.auto_accept:
            handle.status = st.ACTIVE
        self.publish_status()
        task = asyncio.get_running_loop().create_task(self._run(handle))
        self.tasks.add(task)
        task.add_done_callback(self.tasks.discard)

    async def _run(self, handle: ServerGoalHandle) -> None:
        try:
            result = await self.execute(handle)
        except asyncio.CancelledError:
            handle.abort(text="the action server shut down")
            handle.reject(text="the action server shut down")
            raise
        except Exception as err:  # noqa: BLE001 - the goal fails, the server goes on
            handle.abort(text=str(err) or type(err).__name__)
            handle.reject(text=str(err) or type(err).__name__)
            return
        if handle.done:
            return
        if handle.cancel_requested.is_set():
            handle.canceled(result)
        else:
            handle.accept()
            handle.succeed(result)

    def _on_cancel(self, data: bytes) -> None:
        cancel = self.types.codec.decode(st.GOAL_ID, data)
        stamp_ns = cancel.stamp.to_nsec()
        for handle in list(self.goals.values()):
            if st.cancel_matches(cancel.id, stamp_ns, handle.id, handle.stamp.to_nsec()):
                handle._request_cancel()
        self._last_cancel_ns = max(self._last_cancel_ns, stamp_ns)

    async def close(self) -> None:
        """Stop the goals in progress (ABORTED) and the status timer."""
        for task in list(self.tasks):
            task.cancel()
        for task in list(self.tasks):
            with contextlib.suppress(asyncio.CancelledError):
                await task
        if self._timer is not None:
            self._timer.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._timer
