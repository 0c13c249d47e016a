"""What ``rostools node`` asks of the graph: registrations, node URIs, pids, live connections.

Blocking and synchronous, over ``rostools.rosgraph.masterapi``: the master for registrations and
node URIs, each node's slave API (ROS1_PROTOCOL.md §4) for ``getPid``, ``getBusInfo`` and
``shutdown``. Every call to a node has a timeout; a node that does not answer in time raises
``TimeoutExpired``, one that cannot be reached (refused, reset, unknown host) raises
``UnreachableError``, an unknown node ``NotFoundError``.

The pure parts (``SystemState``, ``BusConnection``, ``plan_cleanup``, ``build_graph``,
``nodes_on_machine``) take data and need no network, so they are tested without sockets.
"""

from __future__ import annotations

import http.client
import re
import socket
import time
import xmlrpc.client
from collections.abc import Callable, Iterable, Mapping, Sequence
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass, field
from typing import Any
from urllib.parse import urlsplit

from rostools.errors import NotFoundError, RostoolsError, TimeoutExpired, UnreachableError
from rostools.names import make_global_ns
from rostools.rosgraph.masterapi import (
    NODE_TIMEOUT,
    MasterError,
    MasterProxy,
    TimeoutTransport,
    XmlRpcNode,
)

#: The reason rosnode gives in ``shutdown`` calls (observed on the wire).
KILL_REASON = "user request"
#: Nodes probed at once by ``probe_nodes``: dead nodes cost a timeout each, so run in parallel.
PROBE_WORKERS = 16
#: The text rospy and roscpp put in the last getBusInfo field; rosnode parses it the same way
#: (``rosnode.CONNECTION_PATTERN``, from rospy's ``TCPROSTransport.get_transport_info``).
CONNECTION_INFO = re.compile(r"\w+ connection on port (\d+) to \[(.*) on socket (\d+)\]")
#: Topics and nodes ``build_graph`` leaves out unless asked, as rqt_graph hides "debug" ones:
#: every node publishes /rosout, which would otherwise join every node to every other.
DEBUG_TOPICS = frozenset({"/rosout", "/rosout_agg", "/statistics"})
DEBUG_NODES = frozenset({"/rosout"})


# --------------------------------------------------------------------------- registrations


@dataclass(frozen=True)
class SystemState:
    """The master's ``getSystemState``: topic or service name -> node names."""

    publishers: dict[str, list[str]]
    subscribers: dict[str, list[str]]
    services: dict[str, list[str]]

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


@dataclass(frozen=True)
class Registrations:
    """One node's registrations on the master."""

    publications: list[str]
    subscriptions: list[str]
    services: list[str]


def system_state(master: MasterProxy) -> SystemState:
    """The master's current system state."""
    return SystemState.from_master(master.system_state())


# --------------------------------------------------------------------------- node slave API


@dataclass(frozen=True)
class BusConnection:
    """One entry of a node's ``getBusInfo``: a live topic connection."""

    id: int
    peer: str  # outbound: the subscriber's caller id; inbound: the publisher's XML-RPC URI
    direction: str  # "inbound", "outbound" or "unknown"
    transport: str
    topic: str
    connected: bool
    info: str
    #: Parsed from ``info`` when it has rospy/roscpp's form: our port, the peer's address and
    #: our socket number (None when the node gave something else, e.g. ``socket None``).
    local_port: int | None = None
    remote: str | None = None
    socket: int | None = None

    @classmethod
    def from_bus_info(cls, entry: Sequence[Any]) -> BusConnection:
        """From ``[id, peer, direction, transport, topic, connected?, info?]``."""
        if len(entry) < 5:
            raise RostoolsError(f"bad getBusInfo entry from a node: {list(entry)!r}")
        direction = {"i": "inbound", "o": "outbound"}.get(str(entry[2]), "unknown")
        # Older nodes send five fields: those connections are up (rosnode's reading).
        connected = bool(entry[5]) if len(entry) > 5 else True
        info = str(entry[6]) if len(entry) > 6 else ""
        match = CONNECTION_INFO.match(info)
        conn_id = entry[0]
        return cls(
            id=int(conn_id) if isinstance(conn_id, int) else -1,
            peer=str(entry[1]),
            direction=direction,
            transport=str(entry[3]),
            topic=str(entry[4]),
            connected=connected,
            info=info,
            local_port=int(match.group(1)) if match else None,
            remote=match.group(2) if match else None,
            socket=int(match.group(3)) if match else None,
        )


def _went_away(err: BaseException) -> bool:
    """Whether a failed call failed because the node closed the connection while answering."""
    cause = err.__context__
    return isinstance(
        cause, ConnectionResetError | BrokenPipeError | http.client.RemoteDisconnected
    )


class _OneShotTransport(TimeoutTransport):
    """HTTP with a socket timeout that sends each request once.

    The standard transport sends a request again when the connection drops before the
    answer. A node told to shut down may drop it so, and the second try is then refused:
    that would turn a node that did as asked into one that could not be reached.
    """

    def request(
        self, host: Any, handler: str, request_body: Any, verbose: bool = False
    ) -> tuple[Any, ...]:
        result: tuple[Any, ...] = self.single_request(host, handler, request_body, verbose)
        return result


class NodeApi(XmlRpcNode):
    """Calls to one node's slave API, each with a timeout, each sent once."""

    def __init__(self, name: str, uri: str, caller_id: str, timeout: float) -> None:
        super().__init__(uri, caller_id, timeout, what=f"node {name}")
        self.name = name
        self.proxy = xmlrpc.client.ServerProxy(
            uri, transport=_OneShotTransport(timeout), allow_none=False
        )

    def get_pid(self) -> int:
        """The node's process id."""
        pid = self.call("getPid")
        if not isinstance(pid, int):
            raise RostoolsError(f"the node {self.name} answered getPid with {pid!r}")
        return pid

    def ping(self) -> tuple[int, float]:
        """``getPid`` timed: the pid and the round trip in milliseconds."""
        start = time.perf_counter()
        pid = self.get_pid()
        return pid, (time.perf_counter() - start) * 1000.0

    def bus_info(self) -> list[BusConnection]:
        """The node's connections."""
        entries = self.call("getBusInfo")
        if not isinstance(entries, list):
            raise RostoolsError(f"the node {self.name} answered getBusInfo with {entries!r}")
        return [BusConnection.from_bus_info(e) for e in entries]

    def shutdown(self, reason: str = KILL_REASON) -> None:
        """Ask the node to shut down.

        A node may close the connection before its answer is out (it is shutting down, as
        asked); rosnode counts that as success, and so does this.
        """
        try:
            self.raw("shutdown", reason)
        except UnreachableError as err:
            if not _went_away(err):
                raise


class Graph:
    """The master of one command, with node URIs looked up once and remembered."""

    def __init__(self, master: MasterProxy, timeout: float = NODE_TIMEOUT) -> None:
        self.master = master
        self.timeout = timeout
        self._uris: dict[str, str | None] = {}
        self._state: SystemState | None = None

    def state(self, refresh: bool = False) -> SystemState:
        """The system state, fetched once unless ``refresh``."""
        if self._state is None or refresh:
            self._state = system_state(self.master)
        return self._state

    def uri(self, node: str, refresh: bool = False) -> str | None:
        """The node's XML-RPC URI, or None when the master does not know it."""
        if refresh or node not in self._uris:
            try:
                self._uris[node] = self.master.lookup_node(node)
            except NotFoundError:
                self._uris[node] = None
        return self._uris[node]

    def require_uri(self, node: str) -> str:
        """The node's XML-RPC URI; NotFoundError for an unknown node."""
        uri = self.uri(node)
        if uri is None:
            raise NotFoundError(f"unknown node {node}", hint="see 'rostools node list'")
        return uri

    def api(self, node: str, uri: str | None = None) -> NodeApi:
        """A client of the node's slave API."""
        return NodeApi(node, uri or self.require_uri(node), self.master.caller_id, self.timeout)

    def peer_node(self, topic: str, peer: str) -> str | None:
        """The name of the node whose URI is ``peer`` among those on ``topic`` (as rosnode)."""
        if not peer.startswith(("http://", "https://")):
            return None
        for node in self.state().on_topic(topic):
            if self.uri(node) == peer:
                return node
        return None


# --------------------------------------------------------------------------- info


@dataclass
class NodeInfo:
    """What ``node info`` shows: registrations with types, and (when contacted) the bus."""

    name: str
    uri: str
    publications: list[tuple[str, str]]
    subscriptions: list[tuple[str, str]]
    services: list[str]
    pid: int | None = None
    connections: list[tuple[BusConnection, str | None]] | None = None  # with the peer's name
    error: RostoolsError | None = None  # why the node could not be contacted

    def to_data(self) -> dict[str, Any]:
        """Plain data for JSON and YAML."""
        data: dict[str, Any] = {
            "node": self.name,
            "uri": self.uri,
            "publications": [{"topic": t, "type": ty} for t, ty in self.publications],
            "subscriptions": [{"topic": t, "type": ty} for t, ty in self.subscriptions],
            "services": list(self.services),
        }
        if self.pid is not None:
            data["pid"] = self.pid
        if self.connections is not None:
            data["connections"] = [connection_data(c, name) for c, name in self.connections]
        if self.error is not None:
            data["error"] = str(self.error)
        return data


def connection_data(conn: BusConnection, peer_name: str | None) -> dict[str, Any]:
    """One connection as plain data."""
    inbound = conn.direction == "inbound"
    return {
        "id": conn.id,
        "topic": conn.topic,
        "direction": conn.direction,
        "peer_node": peer_name if inbound else conn.peer,
        "peer_uri": conn.peer if inbound else None,
        "transport": conn.transport,
        "connected": conn.connected,
        "local_port": conn.local_port,
        "remote": conn.remote,
        "socket": conn.socket,
        "info": conn.info,
    }


def node_info(graph: Graph, node: str, contact: bool = True) -> NodeInfo:
    """Registrations of a known node and, if ``contact``, its pid and connections.

    A node that cannot be contacted does not raise: its info carries the ``error``.
    """
    uri = graph.require_uri(node)
    regs = graph.state().registrations(node)
    types = graph.master.topic_types()

    def typed(topics: list[str]) -> list[tuple[str, str]]:
        return [(t, types.get(t, "unknown type")) for t in topics]

    info = NodeInfo(node, uri, typed(regs.publications), typed(regs.subscriptions), regs.services)
    if contact:
        api = graph.api(node, uri)
        try:
            pid, bus = api.get_pid(), api.bus_info()
        except (UnreachableError, TimeoutExpired) as err:
            info.error = err
        else:
            info.pid = pid
            info.connections = [(c, graph.peer_node(c.topic, c.peer)) for c in bus]
    return info


# --------------------------------------------------------------------------- probing, killing


@dataclass(frozen=True)
class Probe:
    """One node's answer to a ``getPid`` probe, or why there was none."""

    node: str
    uri: str | None
    pid: int | None = None
    error: RostoolsError | None = None

    @property
    def alive(self) -> bool:
        """Whether the node answered."""
        return self.error is None


def probe_nodes(graph: Graph, nodes: Sequence[str]) -> list[Probe]:
    """Ping every node once, in parallel; the results in the order of ``nodes``.

    A node the master no longer knows is left out: it has gone already.
    """
    uris = {n: graph.uri(n) for n in nodes}

    def one(node: str) -> Probe | None:
        uri = uris[node]
        if uri is None:
            return None
        try:
            pid, _ = graph.api(node, uri).ping()
        except (UnreachableError, TimeoutExpired) as err:
            return Probe(node, uri, error=err)
        except RostoolsError:
            return Probe(node, uri)  # it answered, if oddly: it is alive
        return Probe(node, uri, pid)

    if not nodes:
        return []
    with ThreadPoolExecutor(max_workers=min(PROBE_WORKERS, len(nodes))) as pool:
        results = list(pool.map(one, nodes))
    return [r for r in results if r is not None]


@dataclass(frozen=True)
class KillResult:
    """The nodes ``shutdown`` was sent to, and those it could not reach."""

    killed: list[str]
    failed: list[tuple[str, RostoolsError]]


def kill_nodes(graph: Graph, nodes: Sequence[str], reason: str = KILL_REASON) -> KillResult:
    """Call ``shutdown(caller_id, reason)`` on each node."""
    killed: list[str] = []
    failed: list[tuple[str, RostoolsError]] = []
    for node in nodes:
        try:
            graph.api(node).shutdown(reason)
        except (NotFoundError, UnreachableError, TimeoutExpired) as err:
            failed.append((node, err))
        else:
            killed.append(node)
    return KillResult(killed, failed)


# --------------------------------------------------------------------------- machines


def host_of(uri: str) -> str | None:
    """The host name in a node URI."""
    return urlsplit(uri).hostname


def addresses(host: str) -> set[str]:
    """The addresses a host name resolves to (empty when it does not resolve)."""
    try:
        infos = socket.getaddrinfo(host, 0, 0, 0, socket.SOL_TCP)
    except (OSError, UnicodeError):
        return set()
    return {str(info[4][0]) for info in infos}


def machines(uris: Mapping[str, str | None]) -> dict[str, list[str]]:
    """Host -> sorted node names, from node -> URI (nodes without a URI are left out)."""
    hosts: dict[str, list[str]] = {}
    for node, uri in uris.items():
        host = host_of(uri) if uri else None
        if host:
            hosts.setdefault(host, []).append(node)
    return {h: sorted(ns) for h, ns in sorted(hosts.items())}


def nodes_on_machine(
    uris: Mapping[str, str | None],
    machine: str,
    resolve: Callable[[str], set[str]] = addresses,
) -> list[str]:
    """The nodes whose URI host is ``machine``, by name or by any address they share.

    NotFoundError when ``machine`` does not resolve to an address (as rosnode refuses).
    """
    wanted = resolve(machine)
    if not wanted:
        raise NotFoundError(f"cannot resolve machine name {machine} to an address")
    cache: dict[str, bool] = {}
    found = []
    for node, uri in uris.items():
        host = host_of(uri) if uri else None
        if not host:
            continue
        if host not in cache:
            cache[host] = host == machine or host in wanted or bool(resolve(host) & wanted)
        if cache[host]:
            found.append(node)
    return sorted(found)


# --------------------------------------------------------------------------- cleanup


@dataclass(frozen=True)
class Unregistration:
    """One call that purges a dead node's registration, made with the node's own caller id."""

    node: str
    method: str  # unregisterPublisher, unregisterSubscriber or unregisterService
    name: str  # the topic or service
    api: str  # the caller_api (topics) or service_api (services) it registered with

    @property
    def kind(self) -> str:
        """publisher, subscriber or service."""
        return self.method.removeprefix("unregister").lower()


def plan_cleanup(
    state: SystemState, dead: Mapping[str, str], service_apis: Mapping[str, str]
) -> list[Unregistration]:
    """The calls that remove every registration of the ``dead`` nodes (name -> XML-RPC URI).

    The master only removes a registration whose caller id and API match what was
    registered, so these are the calls rosnode's cleanup makes: the node's name as caller
    id, its node URI for topics, and the current ``lookupService`` URI for services
    (``service_apis``; a service missing there has gone already and is skipped).
    """
    plan: list[Unregistration] = []
    for node in sorted(dead):
        uri = dead[node]
        for method, table in (
            ("unregisterPublisher", state.publishers),
            ("unregisterSubscriber", state.subscribers),
        ):
            plan += [
                Unregistration(node, method, t, uri) for t in sorted(table) if node in table[t]
            ]
        for srv in sorted(state.services):
            if node in state.services[srv] and srv in service_apis:
                plan.append(Unregistration(node, "unregisterService", srv, service_apis[srv]))
    return plan


def service_apis(graph: Graph, nodes: Iterable[str]) -> dict[str, str]:
    """The current service URI of every service the ``nodes`` provide."""
    wanted = set(nodes)
    apis: dict[str, str] = {}
    for srv, providers in graph.state().services.items():
        if wanted.intersection(providers):
            try:
                apis[srv] = graph.master.lookup_service(srv)
            except NotFoundError:
                continue
    return apis


def apply_cleanup(master_uri: str, plan: Sequence[Unregistration]) -> list[bool]:
    """Make the calls; for each, whether the master removed something."""
    done: list[bool] = []
    proxies: dict[str, MasterProxy] = {}
    for step in plan:
        proxy = proxies.setdefault(step.node, MasterProxy(master_uri, step.node))
        try:
            done.append(proxy.call(step.method, step.name, step.api) == 1)
        except MasterError:
            done.append(False)
    return done


# --------------------------------------------------------------------------- graph


@dataclass
class GraphNode:
    """A node of the graph and the topics it is on."""

    name: str
    publishes: list[str] = field(default_factory=list)
    subscribes: list[str] = field(default_factory=list)
    services: list[str] = field(default_factory=list)


@dataclass
class GraphTopic:
    """A topic with its type and the nodes at each end."""

    name: str
    type: str
    publishers: list[str]
    subscribers: list[str]


@dataclass(frozen=True)
class GraphEdge:
    """Data flows from ``source`` to ``target`` on ``topic``."""

    source: str
    target: str
    topic: str
    type: str


@dataclass
class RosGraph:
    """Nodes, topics and node-to-node edges, all sorted by name."""

    nodes: list[GraphNode]
    topics: list[GraphTopic]
    edges: list[GraphEdge]

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
