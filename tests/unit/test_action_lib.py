"""rostools.action without sockets: goal ids, cancel rules, finding actions, a server's goals."""

from __future__ import annotations

import asyncio
import re
from typing import Any

import pytest

from rostools.action import status as st
from rostools.action.goalid import goal_id
from rostools.action.pattern import action_type, find_actions
from rostools.action.server import ServerGoalHandle
from rostools.action.types import ActionTypes
from rostools.msgs.message import Time
from rostools.msgs.store import BuiltinSource, TypeStore


def test_goal_ids_are_actionlibs() -> None:
    first, stamp = goal_id("/client", Time(12, 5))
    second, _ = goal_id("/client")
    assert first.startswith("/client-") and first.endswith("-12.5") and stamp == Time(12, 5)
    n1 = int(re.fullmatch(r"/client-(\d+)-12\.5", first).group(1))  # type: ignore[union-attr]
    n2 = int(second.split("-")[1])
    assert n2 == n1 + 1  # one count per process, as actionlib keeps it


@pytest.mark.parametrize(
    ("cancel", "goal", "covered"),
    [
        (("", 0), ("/a", 5), True),  # empty id, zero stamp: everything
        (("/a", 0), ("/a", 5), True),
        (("/a", 0), ("/b", 5), False),
        (("", 5), ("/b", 5), True),  # a stamp: every goal at or before it
        (("", 4), ("/b", 5), False),
        (("/a", 4), ("/b", 3), True),  # id and stamp: both sets
    ],
)
def test_cancel_rule(cancel: tuple[str, int], goal: tuple[str, int], covered: bool) -> None:
    assert st.cancel_matches(*cancel, *goal) is covered


def test_status_names() -> None:
    assert [st.name(c) for c in (st.SUCCEEDED, st.RECALLED, 42)] == [
        "SUCCEEDED", "RECALLED", "STATUS_42",
    ]  # fmt: skip


def test_actions_found_from_the_five_topics() -> None:
    types = {
        "/fib/goal": "actionlib/TestActionGoal",
        "/fib/cancel": "actionlib_msgs/GoalID",
        "/fib/status": "actionlib_msgs/GoalStatusArray",
        "/fib/feedback": "actionlib/TestActionFeedback",
        "/fib/result": "actionlib/TestActionResult",
        # four of five topics: not an action
        "/half/goal": "actionlib/TestActionGoal",
        "/half/cancel": "actionlib_msgs/GoalID",
        "/half/status": "actionlib_msgs/GoalStatusArray",
        "/half/result": "actionlib/TestActionResult",
        # five topics, one of the wrong type
        "/odd/goal": "std_msgs/String",
        "/odd/cancel": "actionlib_msgs/GoalID",
        "/odd/status": "actionlib_msgs/GoalStatusArray",
        "/odd/feedback": "x/YActionFeedback",
        "/odd/result": "x/YActionResult",
    }
    pubs = [["/fib/status", ["/server"]], ["/fib/goal", ["/client"]], ["/fib/result", ["/server"]]]
    subs = [["/fib/goal", ["/server"]], ["/fib/feedback", ["/client", "/spy"]]]
    found = find_actions(types, pubs, subs)
    assert [a.as_dict() for a in found] == [
        {
            "name": "/fib",
            "type": "actionlib/TestAction",
            "servers": ["/server"],
            "clients": ["/client", "/spy"],
        }
    ]
    assert action_type("pkg/NavActionGoal") == "pkg/NavAction" and action_type("x/Goal") == ""


class FakeServer:
    """What a goal handle needs of its server: the types, and somewhere to publish."""

    def __init__(self) -> None:
        self.types = ActionTypes(TypeStore([BuiltinSource()]), "actionlib/TestAction")
        self.sent: list[tuple[str, Any]] = []
        self.status_sent = 0

    def publish(self, part: str, message: Any) -> None:
        self.sent.append((part, message))

    def publish_status(self) -> None:
        self.status_sent += 1


def handle(server: FakeServer) -> ServerGoalHandle:
    goal = server.types.message("Goal", goal=3)
    return ServerGoalHandle(server, "/c-1-1.0", Time(1), goal)  # type: ignore[arg-type]


def results(server: FakeServer) -> list[tuple[int, str, int]]:
    return [
        (m.status.status, m.status.text, m.result.result)
        for part, m in server.sent
        if part == "result"
    ]


def test_goal_handle_transitions() -> None:
    async def run() -> None:
        server = FakeServer()
        done = handle(server)
        done.accept()
        done.publish_feedback(feedback=2)
        done.succeed(server.types.message("Result", result=30), "ok")
        done.abort(text="too late")  # an ended goal stays ended
        assert results(server) == [(st.SUCCEEDED, "ok", 30)]
        feedback = server.sent[0][1]
        assert (feedback.feedback.feedback, feedback.status.status) == (2, st.ACTIVE)
        assert feedback.status.goal_id.id == "/c-1-1.0"

        server = FakeServer()
        recalled = handle(server)
        recalled._request_cancel()
        assert recalled.status == st.RECALLING and recalled.cancel_requested.is_set()
        recalled.accept()  # accepting a goal being recalled: the cancel stands
        assert recalled.status == st.PREEMPTING
        recalled.canceled(text="stopped")
        rejected = handle(server)
        rejected.reject("no")
        pending = handle(server)
        pending._request_cancel()
        pending.canceled()
        assert [r[:2] for r in results(server)] == [
            (st.PREEMPTED, "stopped"), (st.REJECTED, "no"), (st.RECALLED, ""),
        ]  # fmt: skip
        assert server.status_sent >= 5  # every change goes out at once

    asyncio.run(run())
