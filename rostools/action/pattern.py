"""Actions in the graph: the five-topic pattern over the master's topics and registrations."""

from __future__ import annotations

from typing import Any, NamedTuple

from rostools.action.status import GOAL_ID, STATUS_ARRAY

#: The topics of an action, below its name.
TOPICS = ("goal", "cancel", "status", "feedback", "result")
#: What each topic's type must be (a suffix for the action's own types).
_EXPECTED = {
    "goal": "ActionGoal",
    "cancel": GOAL_ID,
    "status": STATUS_ARRAY,
    "feedback": "ActionFeedback",
    "result": "ActionResult",
}
#: Who publishes each topic: the server publishes status, feedback and result.
_SERVER_PUBLISHES = ("status", "feedback", "result")


class ActionInfo(NamedTuple):
    """An action found in the graph."""

    name: str
    #: ``pkg/NameAction``, or "" when no topic of it has a type the master knows.
    type: str
    servers: list[str]
    clients: list[str]

    def as_dict(self) -> dict[str, Any]:
        """The record ``action list``/``info`` print."""
        return {
            "name": self.name, "type": self.type, "servers": self.servers, "clients": self.clients
        }  # fmt: skip


def action_type(goal_type: str) -> str:
    """``pkg/NameAction`` from the type of its goal topic (``pkg/NameActionGoal``), or ""."""
    return goal_type.removesuffix("Goal") if goal_type.endswith("ActionGoal") else ""


def _fits(part: str, type_name: str | None) -> bool:
    if not type_name or type_name == "*":
        return True  # not known: the pattern of names decides
    expected = _EXPECTED[part]
    return type_name == expected if "/" in expected else type_name.endswith(expected)


def find_actions(
    types: dict[str, str], publishers: list[Any], subscribers: list[Any]
) -> list[ActionInfo]:
    """Every name with all five topics, of the right types, sorted.

    ``types`` is ``getTopicTypes`` as a dict; ``publishers`` and ``subscribers`` are the first
    two lists of ``getSystemState`` (``[topic, [node, ...]]`` pairs).
    """
    pubs = {t: list(n) for t, n in publishers}
    subs = {t: list(n) for t, n in subscribers}
    topics = set(types) | set(pubs) | set(subs)
    found: list[ActionInfo] = []
    for topic in sorted(topics):
        if not topic.endswith("/goal"):
            continue
        name = topic[: -len("/goal")]
        if not name or any(f"{name}/{p}" not in topics for p in TOPICS):
            continue
        if not all(_fits(p, types.get(f"{name}/{p}")) for p in TOPICS):
            continue
        servers: set[str] = set()
        clients: set[str] = set()
        for part in TOPICS:
            server_side = part in _SERVER_PUBLISHES
            servers.update((pubs if server_side else subs).get(f"{name}/{part}", []))
            clients.update((subs if server_side else pubs).get(f"{name}/{part}", []))
        found.append(
            ActionInfo(name, action_type(types.get(topic, "")), sorted(servers), sorted(clients))
        )
    return found
