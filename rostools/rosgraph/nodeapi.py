"""Asking nodes over their slave API (wiki.ros.org/ROS/Slave_API): pids, bus info, shutdown.

Blocking. Every call to a node has a timeout: a node that does not answer in time raises
``TimeoutExpired``, one that cannot be reached (refused, reset, unknown host)
``UnreachableError``, an unknown node ``NotFoundError``. ``Graph`` puts the master and the
nodes together for ``rostools node``.
"""

from __future__ import annotations

import re
import time

from rostools.errors import NotFoundError, RostoolsError, TimeoutExpired, UnreachableError
from rostools.rosgraph.masterapi import NODE_TIMEOUT, MasterProxy, XmlRpcNode
from rostools.rosgraph.state import SystemState, system_state
from rostools.rosgraph.views import Record

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from collections.abc import Sequence
    from typing import Any

#: The reason rosnode gives in ``shutdown`` calls (observed on the wire).
KILL_REASON = "user request"


#: Nodes probed at once by ``probe_nodes``: dead nodes cost a timeout each, so run in parallel.
PROBE_WORKERS = 16


#: The text rospy and roscpp put in the last getBusInfo field; rosnode parses it the same way
#: (``rosnode.CONNECTION_PATTERN``, from rospy's ``TCPROSTransport.get_transport_info``).
CONNECTION_INFO = re.compile(r"\w+ connection on port (\d+) to \[(.*) on socket (\d+)\]")


class BusConnection(Record):
    """One entry of a node's ``getBusInfo``: a live topic connection."""

    __slots__ = (
        "connected",
        "direction",
        "id",
        "info",
        "local_port",
        "peer",
        "remote",
        "socket",
        "topic",
        "transport",
    )

    def __init__(
        self,
        id: int,
        peer: str,
        direction: str,
        transport: str,
        topic: str,
        connected: bool,
        info: str,
        local_port: int | None = None,
        remote: str | None = None,
        socket: int | None = None,
    ) -> None:
        self.id = id
        #: outbound: the subscriber's caller id; inbound: the publisher's XML-RPC URI
        self.peer = peer
        self.direction = direction  # "inbound", "outbound" or "unknown"
        self.transport = transport
        self.topic = topic
        self.connected = connected
        self.info = info
        #: Parsed from ``info`` when it has rospy/roscpp's form: our port, the peer's address
        #: and our socket number (None when the node gave something else, e.g. ``socket None``).
        self.local_port = local_port
        self.remote = remote
        self.socket = socket

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
    return isinstance(err.__context__, ConnectionResetError | BrokenPipeError | EOFError)


class NodeApi(XmlRpcNode):
    """Calls to one node's slave API, each with a timeout, each sent once.

    A node told to shut down may drop the connection before it answers; sent again, the
    request would be refused, and a node that did as asked would look unreachable.
    """

    def __init__(self, name: str, uri: str, caller_id: str, timeout: float) -> None:
        super().__init__(uri, caller_id, timeout, what=f"node {name}")
        self.name = name
        self.http.retry = False

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


class NodeInfo(Record):
    """What ``node info`` shows: registrations with types, and (when contacted) the bus."""

    __slots__ = (
        "connections",
        "error",
        "name",
        "pid",
        "publications",
        "services",
        "subscriptions",
        "uri",
    )

    def __init__(
        self,
        name: str,
        uri: str,
        publications: list[tuple[str, str]],
        subscriptions: list[tuple[str, str]],
        services: list[str],
        pid: int | None = None,
        connections: list[tuple[BusConnection, str | None]] | None = None,
        error: RostoolsError | None = None,
    ) -> None:
        self.name = name
        self.uri = uri
        self.publications = publications
        self.subscriptions = subscriptions
        self.services = services
        self.pid = pid
        self.connections = connections  # with the peer's name
        self.error = error  # why the node could not be contacted

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


class Probe(Record):
    """One node's answer to a ``getPid`` probe, or why there was none."""

    __slots__ = ("error", "node", "pid", "uri")

    def __init__(
        self,
        node: str,
        uri: str | None,
        pid: int | None = None,
        error: RostoolsError | None = None,
    ) -> None:
        self.node = node
        self.uri = uri
        self.pid = pid
        self.error = error

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
    # Here, not at the top: concurrent.futures brings logging (18 ms), and only ping needs it.
    from concurrent.futures import ThreadPoolExecutor

    with ThreadPoolExecutor(max_workers=min(PROBE_WORKERS, len(nodes))) as pool:
        results = list(pool.map(one, nodes))
    return [r for r in results if r is not None]


class KillResult(Record):
    """The nodes ``shutdown`` was sent to, and those it could not reach."""

    __slots__ = ("failed", "killed")

    def __init__(self, killed: list[str], failed: list[tuple[str, RostoolsError]]) -> None:
        self.killed = killed
        self.failed = failed


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
