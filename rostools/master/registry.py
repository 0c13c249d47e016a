"""Who publishes, subscribes, serves and watches what: rosmaster's registration model.

Pure bookkeeping (https://wiki.ros.org/ROS/Master_API). It never calls out; it returns the
calls the master must make (``shutdown`` of a node replaced by a new one under the same name).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Literal

from rostools.wire.codes import SUCCESS

Kind = Literal["pub", "sub", "srv", "param"]
#: (caller_id, caller_api) pairs registered under one key, in registration order.
Providers = list[tuple[str, str]]


@dataclass
class NodeRef:
    """A node the master knows: its XML-RPC URI and what it has registered."""

    api: str
    registrations: set[tuple[Kind, str]] = field(default_factory=set)


@dataclass
class Outgoing:
    """An XML-RPC call the master owes a node."""

    uri: str
    method: str
    args: tuple[object, ...]


class Registry:
    """The master's registrations."""

    def __init__(self) -> None:
        self.nodes: dict[str, NodeRef] = {}
        self.publishers: dict[str, Providers] = {}
        self.subscribers: dict[str, Providers] = {}
        self.param_subscribers: dict[str, Providers] = {}
        #: service -> (caller_id, caller_api, service_api); the last registration wins.
        self.services: dict[str, tuple[str, str, str]] = {}
        #: topic -> type, while anyone publishes or subscribes it. rosmaster keeps every
        #: type forever, so a master that sees many short-lived topic names grows without
        #: end; rostopic and rospy only look up types of topics in the graph.
        self.topic_types: dict[str, str] = {}

    def _multimap(self, kind: Kind) -> dict[str, Providers]:
        if kind == "pub":  # no table of tables: a register call looks up three or four
            return self.publishers
        if kind == "sub":
            return self.subscribers
        if kind == "param":
            return self.param_subscribers
        raise KeyError(kind)

    def _node(self, caller_id: str, caller_api: str) -> tuple[NodeRef, list[Outgoing]]:
        node = self.nodes.get(caller_id)
        if node is not None and node.api == caller_api:
            return node, []
        calls: list[Outgoing] = []
        if node is not None:
            # Same name, new URI: tell the old one to go, forget all it registered.
            reason = f"[{caller_id}] Reason: new node registered with same name"
            calls.append(Outgoing(node.api, "shutdown", ("/master", reason)))
            self._purge(caller_id)
        node = self.nodes[caller_id] = NodeRef(caller_api)
        return node, calls

    def _purge(self, caller_id: str) -> None:
        for table in (self.publishers, self.subscribers, self.param_subscribers):
            for key in list(table):
                table[key] = [p for p in table[key] if p[0] != caller_id]
                if not table[key]:
                    del table[key]
                    self._forget_type(key)
        for service, (cid, _, _) in list(self.services.items()):
            if cid == caller_id:
                del self.services[service]

    def _forget_type(self, topic: str) -> None:
        if topic not in self.publishers and topic not in self.subscribers:
            self.topic_types.pop(topic, None)

    def register(
        self, kind: Kind, key: str, caller_id: str, caller_api: str, service_api: str = ""
    ) -> list[Outgoing]:
        """Record a registration; the calls it makes necessary."""
        node, calls = self._node(caller_id, caller_api)
        node.registrations.add((kind, key))
        if kind == "srv":
            self.services[key] = (caller_id, caller_api, service_api)
        else:
            providers = self._multimap(kind).setdefault(key, [])
            if (caller_id, caller_api) not in providers:
                providers.append((caller_id, caller_api))
        return calls

    def unregister(
        self, kind: Kind, key: str, caller_id: str, caller_api: str = "", service_api: str = ""
    ) -> tuple[int, str, int]:
        """Remove a registration; rosmaster's ``[1, message, removed]`` answer."""
        node = self.nodes.get(caller_id)
        if node is None:
            return SUCCESS, f"[{caller_id}] is not a registered node", 0
        if kind == "srv":
            current = self.services.get(key)
            if current is None:
                answer = (1, f"[{caller_id}] is not a provider of [{key}]", 0)
            elif (current[0], current[2]) != (caller_id, service_api):
                answer = (
                    1,
                    f"[{service_api}] is no longer the current service api handle for [{key}]",
                    0,
                )
            else:
                del self.services[key]
                answer = (1, f"Unregistered [{caller_id}] as provider of [{key}]", 1)
        else:
            table = self._multimap(kind)
            providers = table.get(key, [])
            if (caller_id, caller_api) in providers:
                providers.remove((caller_id, caller_api))
                if not providers:
                    del table[key]
                    self._forget_type(key)
                answer = (1, f"Unregistered [{caller_id}] as provider of [{key}]", 1)
            else:
                answer = (1, f"[{caller_id}] is not a known provider of [{key}]", 0)
        if answer[2] == 1:
            node.registrations.discard((kind, key))
        if not node.registrations:
            del self.nodes[caller_id]
        return answer

    def apis(self, kind: Kind, key: str) -> list[str]:
        """The XML-RPC URIs registered under a key."""
        return [api for _, api in self._multimap(kind).get(key, [])]

    def state(self) -> list[list[list[Any]]]:
        """``getSystemState``: publishers, subscribers, services as ``[name, [nodes]]``."""
        pubs = [[t, [cid for cid, _ in p]] for t, p in self.publishers.items()]
        subs = [[t, [cid for cid, _ in p]] for t, p in self.subscribers.items()]
        srvs = [[s, [cid]] for s, (cid, _, _) in self.services.items()]
        return [pubs, subs, srvs]
