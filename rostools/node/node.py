"""A ROS node on asyncio: its slave API, its TCPROS server, registration and clean exit.

The node answers the whole slave API as rospy does (wiki.ros.org/ROS/Slave_API), accepts topic
subscribers and service clients on one TCPROS port, and registers everything it offers
with the master. ``close()`` unregisters all of it.
"""

from __future__ import annotations

import asyncio
import logging
import os
from collections.abc import Callable
from typing import Any

from rostools.msgs.topictype import ANY, ServiceType, TopicType
from rostools.names import anonymous, canonicalize, make_global_ns, resolve, ros_namespace
from rostools.node.connection import ConnectionHandler, Pending, ServerConnection
from rostools.node.listen import Listener, listen
from rostools.node.mastercalls import LiveMaster, uris_of
from rostools.node.notice import Notice, to_stderr
from rostools.node.publisher import TopicPublisher
from rostools.node.registration import Registrar, Registration
from rostools.node.rpc import XmlRpcServer
from rostools.node.service import ServiceHandler, ServiceServer
from rostools.node.subscriber import FramesCallback, Subscriber
from rostools.node.watch import MasterWatch
from rostools.rosgraph.network import bind_address, host_name
from rostools.wire import rosapi as check
from rostools.wire.codes import ERROR, FAILURE, SUCCESS
from rostools.wire.rosapi import Methods, Triple
from rostools.wire.tcpros import error_header
from rostools.wire.xmlrpc import multicall

log = logging.getLogger(__name__)


class LiveNode:
    """A ROS node: ``await LiveNode(...).start()``, then advertise and subscribe."""

    def __init__(
        self,
        name: str,
        master_uri: str,
        *,
        anonymous_name: bool = False,
        ns: str | None = None,
        remappings: dict[str, str] | None = None,
        host: str | None = None,
        logger_services: bool = True,
    ) -> None:
        """A node named ``name`` in ``ns`` (default: ``ROS_NAMESPACE``).

        ``logger_services``: serve ``~get_loggers`` and ``~set_logger_level`` as rospy's
        nodes do (``node/loggers.py``), registered in the background once the node starts.

        ``remappings`` are command-line ``name:=value`` pairs: ``__name``, ``__ns``,
        ``__master``, ``__ip``/``__hostname``, ``_private`` parameters and topic remaps.
        """
        args = dict(remappings or {})
        if "__name" in args:
            name, anonymous_name = args.pop("__name"), False
        ns = args.pop("__ns", ns)
        master_uri = args.pop("__master", master_uri)
        given: dict[str, str] = {k: args.pop(k) for k in ("__hostname", "__ip") if k in args}
        args.pop("__log", None)
        base = anonymous(name.strip("/")) if anonymous_name else name.strip("/")
        ns = make_global_ns(ns) if ns else ros_namespace()
        self.name = (
            canonicalize(ns + "/" + base) if not name.startswith("/") else canonicalize(name)
        )
        self.master_uri = master_uri
        #: The master, typed: every call this node makes to it.
        self.master = LiveMaster(master_uri, self.name)
        # by rosgraph's rules: a __hostname:=/__ip:= argument, the given host, then the environment
        self.host = host_name(remappings=given) if given or not host else host
        #: ``_param:=value`` arguments, set as private parameters when the node starts.
        self.private_params = {k[1:]: v for k, v in args.items() if k.startswith("_")}
        self.remappings = {
            resolve(k, self.name): resolve(v, self.name)
            for k, v in args.items()
            if not k.startswith("_")
        }
        self.publishers: dict[str, TopicPublisher] = {}
        self.subscribers: dict[str, Subscriber] = {}
        self.services: dict[str, ServiceServer] = {}
        self.shutdown_requested = asyncio.Event()
        self.shutdown_reason = ""
        #: Where the node's notices go (a peer it cannot reach, a master restart).
        self.notify: Callable[[Notice], None] = to_stderr
        #: Called with each ``paramUpdate`` (key, value) once the node follows parameters.
        self.on_param_update: Callable[[str, Any], None] | None = None
        self._xmlrpc: XmlRpcServer | None = None
        self._tcpros: Listener | None = None
        self._watch: MasterWatch | None = None
        #: Registrations, and those the master was too slow to take, tried again.
        self.registrar = Registrar(self)
        #: Set while the master does not answer (see ``MasterWatch``).
        self.master_lost = False
        self._conn_ids = 0
        self.tcpros_port = 0
        self._methods = self._slave_api()
        self._logger_services = logger_services
        self._loggers_task: asyncio.Task[None] | None = None

    # life cycle -----------------------------------------------------------------------

    async def start(self) -> LiveNode:
        """Start the slave API and TCPROS servers."""
        bind = bind_address(self.host)
        self._xmlrpc = XmlRpcServer(self._dispatch, bind, 0)
        await self._xmlrpc.start()
        pending = Pending()  # connections still to send their header, at most MAX_PENDING
        self._tcpros = await listen(lambda: ServerConnection(self._accept, pending), bind, 0)
        self.tcpros_port = self._tcpros.port
        if self.private_params:
            from rostools import yamlio

            for key, text in self.private_params.items():
                value = yamlio.load(text, f"_{key}:=") if text else ""
                await self.master.set_param(f"{self.name}/{key}", value)
        self._watch = MasterWatch(self)
        self._watch.start()
        if self._logger_services:
            # not awaited: a command's own registrations need not wait for these
            self._loggers_task = asyncio.get_running_loop().create_task(self._serve_loggers())
        return self

    async def _serve_loggers(self) -> None:
        from rostools.node.loggers import serve_loggers

        try:
            await serve_loggers(self)
        except Exception as err:  # noqa: BLE001 - the node works without them; say why at debug
            log.debug("serving the logger services failed: %s", err)

    @property
    def uri(self) -> str:
        """The slave API URI this node registers with."""
        assert self._xmlrpc is not None, "start() the node first"
        return f"http://{self.host}:{self._xmlrpc.port}/"

    def resolve(self, name: str) -> str:
        """A topic or service name as this node sees it (namespace, remappings)."""
        return resolve(name, self.name, self.remappings)

    def next_connection_id(self) -> int:
        """A connection id unique within this node."""
        self._conn_ids += 1
        return self._conn_ids

    async def close(self) -> None:
        """Unregister everything, close every connection and server."""
        if self._watch is not None:
            self._watch.stop()
        if self._loggers_task is not None:
            self._loggers_task.cancel()
        self.registrar.close()
        calls = self.unregister_calls()
        if calls:
            try:
                await self.master.multicall(calls)
            except Exception as err:  # noqa: BLE001 - leaving anyway; the master may be gone
                log.debug("unregistering from %s failed: %s", self.master_uri, err)
        for sub in list(self.subscribers.values()):
            await sub.close()
        for pub in self.publishers.values():
            pub.close()
        for server in self.services.values():
            server.close()
        if self._tcpros is not None:
            self._tcpros.close()
        if self._xmlrpc is not None:
            await self._xmlrpc.close()

    def unregister_calls(self) -> list[tuple[str, tuple[Any, ...]]]:
        """The master calls (method, arguments after the caller id) that undo our registrations."""
        calls: list[tuple[str, tuple[Any, ...]]] = []
        for topic in list(self.publishers):
            calls.append(("unregisterPublisher", (topic, self.uri)))
        for topic in list(self.subscribers):
            calls.append(("unregisterSubscriber", (topic, self.uri)))
        for service, server in list(self.services.items()):
            calls.append(("unregisterService", (service, server.uri)))
        return calls

    # master calls ---------------------------------------------------------------------

    async def advertise(
        self, topic: str, topic_type: TopicType, latch: bool = False, queue_size: int = 100
    ) -> TopicPublisher:
        """Publish on ``topic`` (registered with the master)."""
        topic = self.resolve(topic)
        pub = self.publishers.get(topic)
        if pub is None:
            new = self.publishers[topic] = TopicPublisher(
                self, topic, topic_type, latch, queue_size
            )

            def take(answer: Any) -> None:
                new.reported = uris_of(answer)

            await self.registrar.register(
                Registration(
                    f"publication {topic}",
                    "registerPublisher",
                    (topic, topic_type.type, self.uri),
                    take,
                    lambda: self.publishers.get(topic) is new and not new.closed,
                )
            )
            pub = new
        return pub

    async def subscribe(
        self,
        topic: str,
        callback: FramesCallback,
        topic_type: TopicType = ANY,
        tcp_nodelay: bool = False,
        on_header: Callable[[Any], None] | None = None,
        *,
        coalesce: float = 0.0,
        reuse_frames: bool = False,
    ) -> Subscriber:
        """Subscribe to ``topic``; ``topic_type`` ``ANY`` learns it from the publisher.

        ``coalesce`` and ``reuse_frames`` are for callbacks that only count or measure
        (``Subscriber``'s attributes of those names).
        """
        topic = self.resolve(topic)
        sub = Subscriber(self, topic, topic_type, callback, tcp_nodelay)
        sub.on_header = on_header
        sub.coalesce, sub.reuse_frames = coalesce, reuse_frames
        self.subscribers[topic] = sub
        await self.registrar.register(
            Registration(
                f"subscription {topic}",
                "registerSubscriber",
                (topic, topic_type.type, self.uri),
                lambda answer: sub.update(uris_of(answer)),
                lambda: self.subscribers.get(topic) is sub and not sub.closed,
            )
        )
        return sub

    async def unsubscribe(self, topic: str) -> None:
        """Close the subscription to ``topic`` and withdraw it from the master."""
        topic = self.resolve(topic)
        sub = self.subscribers.pop(topic, None)
        if sub is not None:
            await sub.close()
            await self.master.unregister_subscriber(topic, self.uri)

    async def unadvertise(self, topic: str) -> None:
        """Stop publishing on ``topic`` and withdraw it from the master."""
        topic = self.resolve(topic)
        pub = self.publishers.pop(topic, None)
        if pub is not None:
            pub.close()
            await self.master.call("unregisterPublisher", topic, self.uri)

    async def advertise_service(
        self, name: str, srv_type: ServiceType, handler: ServiceHandler, *, quiet: bool = False
    ) -> ServiceServer:
        """Serve ``name`` (registered with the master).

        ``quiet``: a master slow to take it is not said (the node's own logger services).
        """
        name = self.resolve(name)
        server = self.services[name] = ServiceServer(self, name, srv_type, handler)
        await self.registrar.register(
            Registration(
                f"service {name}",
                "registerService",
                (name, server.uri, self.uri),
                lambda _: None,
                lambda: self.services.get(name) is server,
                quiet,
            )
        )
        return server

    async def unadvertise_service(self, name: str) -> None:
        """Stop serving ``name`` and withdraw it from the master."""
        name = self.resolve(name)
        server = self.services.pop(name, None)
        if server is not None:
            server.close()
            await self.master.call("unregisterService", name, server.uri)

    # TCPROS ---------------------------------------------------------------------------

    def _accept(self, fields: dict[str, str], conn: ServerConnection) -> ConnectionHandler | None:
        if "topic" in fields:
            pub = self.publishers.get(fields["topic"])
            if pub is None:
                topics = sorted(self.publishers)
                problem = (
                    f"[{self.name}] is not a publisher of [{fields['topic']}]. Topics are {topics}"
                )
                conn.write(error_header(problem))
                conn.close()
                return None
            return pub.accept(fields, conn)
        if "service" in fields:
            server = self.services.get(fields["service"])
            if server is None:
                conn.write(
                    error_header(f"[{self.name}] is not a provider of  [{fields['service']}]")
                )
                conn.close()
                return None
            handler: ConnectionHandler | None = server.accept(fields, conn)
            return handler
        conn.write(error_header("no topic or service name detected"))
        conn.close()
        return None

    # slave API ------------------------------------------------------------------------

    def _slave_api(self) -> Methods:
        """The slave API with rospy's error values and argument checks (``masterslave``)."""
        topic = check.graph_name("topic")
        return {
            "getBusStats": (lambda caller: self._bus_stats(), [], ()),
            "getBusInfo": (lambda caller: self._bus_info(), [], ()),
            "getMasterUri": (lambda caller: (1, self.master_uri, self.master_uri), "", ()),
            "shutdown": (self._shutdown, 0, (check.anything,)),
            "getPid": (lambda caller: (1, "", os.getpid()), -1, ()),
            "getSubscriptions": (self._subscriptions, [], ()),
            "getPublications": (self._publications, [], ()),
            "paramUpdate": (
                self._param_update, -1, (check.global_name("parameter_key"), check.anything),
            ),
            "publisherUpdate": (
                self._publisher_update, -1, (topic, check.uri_list("publishers")),
            ),
            "requestTopic": (self._request_topic, [], (topic, check.non_empty("protocols"))),
            "getUri": (lambda caller: (1, "", self.uri), "", ()),
            "getName": (lambda caller: (1, "", self.name), "", ()),
        }  # fmt: skip

    def _dispatch(self, method: str, params: tuple[Any, ...]) -> Any:
        if method == "system.multicall":
            return multicall(self._dispatch, params)
        return check.dispatch(self._methods, method, params)

    def _shutdown(self, caller: str, reason: Any) -> Triple:
        self.shutdown_reason = str(reason)
        self.shutdown_requested.set()
        return SUCCESS, "shutdown", 0

    def _subscriptions(self, caller: str) -> Triple:
        return SUCCESS, "subscriptions", [[t, s.type.type] for t, s in self.subscribers.items()]

    def _publications(self, caller: str) -> Triple:
        return SUCCESS, "publications", [[t, p.type.type] for t, p in self.publishers.items()]

    def _param_update(self, caller: str, key: str, value: Any) -> Triple:
        if self.on_param_update is None:
            return ERROR, "not subscribed", 0
        self.on_param_update(key, value)
        return SUCCESS, "", 0

    def _publisher_update(self, caller: str, topic: str, uris: list[str]) -> Triple:
        sub = self.subscribers.get(self.resolve(topic))
        if sub is not None:
            sub.update(uris)
        return SUCCESS, "", 0

    def _request_topic(self, caller: str, topic: str, protocols: Any) -> Triple:
        topic = self.resolve(topic)
        pub = self.publishers.get(topic)
        if pub is None:
            return ERROR, f"Not a publisher of [{topic}]", []
        pub.contacted.add(caller)  # it reaches us (see MasterWatch)
        for proto in protocols if isinstance(protocols, list) else []:
            if isinstance(proto, list) and proto and proto[0] == "TCPROS":
                return SUCCESS, f"ready on {self.host}:{self.tcpros_port}", [
                    "TCPROS", self.host, self.tcpros_port
                ]  # fmt: skip
        return FAILURE, "no supported protocol implementations", []

    def _bus_stats(self) -> Triple:
        pubs = [
            [t, sum(link.bytes_sent for link in p.links),
             [[link.id, link.bytes_sent, link.messages_sent, True] for link in p.links]]
            for t, p in self.publishers.items()
        ]  # fmt: skip
        subs = [[t, s.stats()] for t, s in self.subscribers.items()]
        return SUCCESS, "", [pubs, subs, []]

    def _bus_info(self) -> Triple:
        info: list[Any] = []
        for topic, pub in self.publishers.items():
            for link in pub.links:
                text = f"TCPROS connection on port {self.tcpros_port} to [{link.conn.peer}]"
                info.append([link.id, link.peer, "o", "TCPROS", topic, True, text])
        for topic, sub in self.subscribers.items():
            for uri, conn in sub.connections.items():
                text = f"TCPROS connection to [{conn.peer}]"
                info.append([conn.id, uri, "i", "TCPROS", topic, True, text])
        return SUCCESS, "bus info", info
