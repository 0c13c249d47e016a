"""A snapshot of the graph: who publishes, subscribes and serves what, and the graph view.

Pure data from ``getSystemState`` (``SystemState``) and the tree of nodes and topics that
``rostools node graph`` draws (``build_graph``); no network, so tested without sockets.
"""

from __future__ import annotations

from rostools.names import make_global_ns
from rostools.rosgraph.views import Record

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from collections.abc import Iterable, Mapping, Sequence
    from typing import Any

    from rostools.rosgraph.masterapi import MasterProxy


#: Topics and nodes ``build_graph`` leaves out unless asked, as rqt_graph hides "debug" ones:
#: every node publishes /rosout, which would otherwise join every node to every other.
DEBUG_TOPICS = frozenset({"/rosout", "/rosout_agg", "/statistics"})


DEBUG_NODES = frozenset({"/rosout"})


class SystemState(Record):
    """The master's ``getSystemState``: topic or service name -> node names."""

    __slots__ = ("publishers", "services", "subscribers")

    def __init__(
        self,
        publishers: dict[str, list[str]],
        subscribers: dict[str, list[str]],
        services: dict[str, list[str]],
    ) -> None:
        self.publishers = publishers
        self.subscribers = subscribers
        self.services = services

    @classmethod
    def from_master(cls, raw: Sequence[Any]) -> SystemState:
        """From the ``[publishers, subscribers, services]`` lists the master returns."""
        pubs, subs, srvs = raw

        def table(rows: Iterable[Any]) -> dict[str, list[str]]:
            out: dict[str, list[str]] = {}
            for name, nodes in rows:
                out.setdefault(str(name), []).extend(str(n) for n in nodes)
            return out

        return cls(table(pubs), table(subs), table(srvs))

    def nodes(self, namespace: str | None = None) -> list[str]:
        """Sorted node names with at least one registration, under ``namespace`` if given.

        As rosnode: a node matches a namespace when it is inside it or is named exactly so.
        """
        names = {
            n
            for table in (self.publishers, self.subscribers, self.services)
            for v in table.values()
            for n in v
        }
        if namespace and namespace != "/":
            prefix = make_global_ns(namespace)
            names = {n for n in names if n.startswith(prefix) or n == namespace}
        return sorted(names)

    def registrations(self, node: str) -> Registrations:
        """What ``node`` publishes, subscribes to and provides, each sorted."""
        return Registrations(
            publications=sorted(t for t, ns in self.publishers.items() if node in ns),
            subscriptions=sorted(t for t, ns in self.subscribers.items() if node in ns),
            services=sorted(s for s, ns in self.services.items() if node in ns),
        )

    def on_topic(self, topic: str) -> list[str]:
        """The publishers, then the subscribers, of ``topic`` (rosnode's peer search order)."""
        return self.publishers.get(topic, []) + self.subscribers.get(topic, [])


class Registrations(Record):
    """One node's registrations on the master."""

    __slots__ = ("publications", "services", "subscriptions")

    def __init__(
        self, publications: list[str], subscriptions: list[str], services: list[str]
    ) -> None:
        self.publications = publications
        self.subscriptions = subscriptions
        self.services = services


def system_state(master: MasterProxy) -> SystemState:
    """The master's current system state."""
    return SystemState.from_master(master.system_state())


class GraphNode(Record):
    """A node of the graph and the topics it is on."""

    __slots__ = ("name", "publishes", "services", "subscribes")

    def __init__(self, name: str) -> None:
        self.name = name
        self.publishes: list[str] = []
        self.subscribes: list[str] = []
        self.services: list[str] = []


class GraphTopic(Record):
    """A topic with its type and the nodes at each end."""

    __slots__ = ("name", "publishers", "subscribers", "type")

    def __init__(
        self,
        name: str,
        type: str,
        publishers: list[str],
        subscribers: list[str],
    ) -> None:
        self.name = name
        self.type = type
        self.publishers = publishers
        self.subscribers = subscribers


class GraphEdge(Record):
    """Data flows from ``source`` to ``target`` on ``topic``."""

    __slots__ = ("source", "target", "topic", "type")

    def __init__(self, source: str, target: str, topic: str, type: str) -> None:
        self.source = source
        self.target = target
        self.topic = topic
        self.type = type


class RosGraph(Record):
    """Nodes, topics and node-to-node edges, all sorted by name."""

    __slots__ = ("edges", "nodes", "topics")

    def __init__(
        self, nodes: list[GraphNode], topics: list[GraphTopic], edges: list[GraphEdge]
    ) -> None:
        self.nodes = nodes
        self.topics = topics
        self.edges = edges

    def node(self, name: str) -> GraphNode:
        """A node by name."""
        return next(n for n in self.nodes if n.name == name)

    def topic(self, name: str) -> GraphTopic:
        """A topic by name."""
        return next(t for t in self.topics if t.name == name)

    def to_data(self) -> dict[str, Any]:
        """Plain data for JSON and YAML."""
        return {
            "nodes": [
                {
                    "name": n.name,
                    "publishes": n.publishes,
                    "subscribes": n.subscribes,
                    "services": n.services,
                }
                for n in self.nodes
            ],
            "topics": [
                {
                    "name": t.name,
                    "type": t.type,
                    "publishers": t.publishers,
                    "subscribers": t.subscribers,
                }
                for t in self.topics
            ],
            "edges": [
                {"source": e.source, "target": e.target, "topic": e.topic, "type": e.type}
                for e in self.edges
            ],
        }


def build_graph(
    state: SystemState, types: Mapping[str, str], include_debug: bool = False
) -> RosGraph:
    """The graph of who talks to whom, from registrations alone (as rqt_graph draws it).

    Without ``include_debug``, /rosout and friends (``DEBUG_TOPICS``, ``DEBUG_NODES``) are
    left out, so that the logging every node does does not hide the data flow.
    """

    def keep_node(n: str) -> bool:
        return include_debug or n not in DEBUG_NODES

    def keep_topic(t: str) -> bool:
        return include_debug or t not in DEBUG_TOPICS

    nodes = {n: GraphNode(n) for n in state.nodes() if keep_node(n)}
    for srv, providers in state.services.items():
        for n in providers:
            if n in nodes:
                nodes[n].services.append(srv)
    topics: dict[str, GraphTopic] = {}
    for topic in sorted(set(state.publishers) | set(state.subscribers)):
        if not keep_topic(topic):
            continue
        pubs = sorted({n for n in state.publishers.get(topic, []) if n in nodes})
        subs = sorted({n for n in state.subscribers.get(topic, []) if n in nodes})
        if not pubs and not subs:
            continue
        topics[topic] = GraphTopic(topic, types.get(topic, "unknown type"), pubs, subs)
        for n in pubs:
            nodes[n].publishes.append(topic)
        for n in subs:
            nodes[n].subscribes.append(topic)
    for entry in nodes.values():
        entry.services.sort()
    edges = [
        GraphEdge(p, s, t.name, t.type)
        for t in topics.values()
        for p in t.publishers
        for s in t.subscribers
    ]
    edges.sort(key=lambda e: (e.source, e.target, e.topic))
    return RosGraph(list(nodes.values()), list(topics.values()), edges)
