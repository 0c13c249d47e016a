"""The bridge: a ROS node with a WebSocket face, in the Foxglove protocol and rosbridge v2.

It runs on the node's own event loop. The graph comes from ``GraphWatch``; each topic the
options choose is a channel; a client's subscription subscribes the node to the topic (the
first one) and lets go of it (the last one); frames go to each client through its own queue
(``client.Client``). A client that offers a Foxglove subprotocol is served by
``operations.py``, any other by ``rosbridge.py`` (``--protocol`` restricts it).
"""

from __future__ import annotations

import asyncio
import hmac
import logging
import time
from collections.abc import Callable, Sequence
from functools import partial
from http import HTTPStatus
from typing import Any
from urllib.parse import parse_qs, urlsplit

from rostools.errors import NotFoundError, RostoolsError
from rostools.msgs.store import TypeStore
from rostools.msgs.topictype import TopicType
from rostools.node.connection import Frame, InboundConnection
from rostools.node.node import LiveNode
from rostools.selection import Selection
from rostools.web.channels import Channel, Links
from rostools.web.client import Client
from rostools.web.graph import GraphChange, GraphWatch
from rostools.web.operations import Operations
from rostools.web.options import BridgeOptions
from rostools.web.rbclient import RosbridgeClient
from rostools.web.rbservices import RbServices
from rostools.web.rosapi import RosApi
from rostools.web.rosbridge import RosbridgeOps
from rostools.web.services import Service
from rostools.web.state import BridgeState, Event
from rostools.wire import foxglove

log = logging.getLogger(__name__)

#: The largest message a client may send (a frame past it closes that client, code 1009).
MAX_CLIENT_MESSAGE = 16 * 1024 * 1024
#: Bytes the socket library may buffer per client before a send waits.
WRITE_LIMIT = 1024 * 1024
#: The least time between two ``time`` messages (a 1 kHz ``/clock`` is sent at 100 Hz).
TIME_PERIOD = 0.01


class Bridge(BridgeState):
    """Serves the graph of ``node`` to WebSocket clients until ``run``'s ``stop``."""

    def __init__(
        self,
        node: LiveNode,
        opts: BridgeOptions,
        store: TypeStore,
        on_event: Callable[[Event], None] | None = None,
    ) -> None:
        super().__init__(node, opts, store, on_event)
        self.selection = Selection(opts)
        self.links = Links(node, self.clock.now, time.monotonic, self._learnt)
        self.graph = GraphWatch(node.master, self._graph_changed)
        self.ops = Operations(self)
        self.rosapi = RosApi(node, store)
        self.rosbridge = RosbridgeOps(self, RbServices(self, self.rosapi))
        self._last_time = 0.0

    # the run -------------------------------------------------------------------------------

    async def run(self, stop: asyncio.Event, ready: Callable[[Bridge], None] | None = None) -> None:
        """Serve until ``stop``; ``ready`` is called once the port is open and the graph read."""
        from websockets.asyncio.server import serve

        tls = self.opts.tls()
        await self.clock.start(self.node)
        if self.clock.sim:
            self.links.borrowed.add("/clock")
            self.clock.forward = self._clock_frames
        try:
            server = await serve(
                self._serve,
                self.opts.address,
                self.opts.port,
                select_subprotocol=self._choose,  # type: ignore[arg-type]
                process_request=self._check_token,
                ssl=tls,
                max_size=MAX_CLIENT_MESSAGE,
                compression=None,
                write_limit=WRITE_LIMIT,
                server_header=None,
            )
        except OSError as err:
            raise RostoolsError(
                f"cannot listen on {self.opts.address}:{self.opts.port}: {err.strerror or err}",
                hint="another bridge may be running there: choose another --port",
            ) from err
        watch = asyncio.get_running_loop().create_task(self.graph.run())
        try:
            self.port = server.sockets[0].getsockname()[1] if server.sockets else self.opts.port
            await self._first_look(stop)
            if self.opts.protocol != "foxglove":
                await self._serve_rosapi()
            self.event("listening", address=self.opts.address, port=self.port, url=self.url)
            if ready is not None:
                ready(self)
            await stop.wait()
        finally:
            watch.cancel()
            server.close()
            for client in list(self.clients):
                client.close()
            await server.wait_closed()
            for task in list(self._tasks):
                task.cancel()

    async def _serve_rosapi(self) -> None:
        """rosapi's services to the graph too, unless a rosapi_node serves them already."""
        try:
            await self.node.master.lookup_service("/rosapi/topics")
        except NotFoundError:
            await self.rosapi.advertise()
            return
        except RostoolsError as err:  # the master went away: the graph watch says so
            log.debug("rosapi: %s", err)
            return
        self.event("warning", message="a rosapi node serves /rosapi/* already: left to it")

    async def _first_look(self, stop: asyncio.Event) -> None:
        """Wait for the first look at the graph (a master that is not there: keep trying)."""
        ready = asyncio.ensure_future(self.graph.ready.wait())
        stopped = asyncio.ensure_future(stop.wait())
        try:
            await asyncio.wait([ready, stopped], return_when=asyncio.FIRST_COMPLETED)
        finally:
            ready.cancel()
            stopped.cancel()

    # clients -----------------------------------------------------------------------------

    def _check_token(self, connection: Any, request: Any) -> Any:
        """Refuse a client without the token, before the upgrade (HTTP 401)."""
        if not self.opts.token:
            return None
        given = parse_qs(urlsplit(request.path).query).get("token", [""])[0]
        if hmac.compare_digest(given.encode(), self.opts.token.encode()):
            return None
        peer = connection.remote_address
        self.event("refused", client=_peer_name(peer), reason="wrong or missing token")
        return connection.respond(HTTPStatus.UNAUTHORIZED, "a token is needed: ?token=...\n")

    def _choose(self, connection: Any, offered: Sequence[str]) -> str | None:
        """A Foxglove subprotocol the client offers, else none: rosbridge v2 (``--protocol``)."""
        from websockets.exceptions import NegotiationError

        if self.opts.protocol != "rosbridge":
            for name in foxglove.SUBPROTOCOLS:
                if name in offered:
                    return name
        if self.opts.protocol == "foxglove":
            raise NegotiationError(
                f"this bridge speaks the Foxglove protocol only: offer {foxglove.SUBPROTOCOLS[0]}"
            )
        return None

    async def _serve(self, ws: Any) -> None:
        from websockets.exceptions import ConnectionClosed

        name = _peer_name(ws.remote_address)
        let_go: Callable[[Client], None] = lambda c: self.spawn(ws.close(1008, "let go"))  # noqa: E731
        client: Client
        if ws.subprotocol in foxglove.SUBPROTOCOLS:
            client = Client(ws, name, let_go)
            handle = partial(self.ops.handle, client)
        else:
            client = rosbridge = RosbridgeClient(ws, name, let_go)
            handle = partial(self.rosbridge.handle, rosbridge)
        self.clients.add(client)
        self.event("connected", client=name, protocol=ws.subprotocol or "rosbridge")
        if client.foxglove:
            self._greet(client)
        try:
            async for message in ws:
                if client.closed:
                    break
                await handle(message)
        except ConnectionClosed:
            pass
        finally:
            await self._drop(client)

    def _greet(self, client: Client) -> None:
        """What a Foxglove client is told first: the server, its channels and services."""
        client.send(self._server_info())
        if self.channels:
            client.send(
                {"op": "advertise", "channels": [c.advertisement() for c in self.channels.values()]}
            )
        if self.services:
            client.send(self._services_message(list(self.services.values())))

    def _server_info(self) -> dict[str, Any]:
        caps = [
            foxglove.PARAMETERS, foxglove.PARAMETERS_SUBSCRIBE, foxglove.CONNECTION_GRAPH,
            foxglove.SERVICES,
        ]  # fmt: skip
        if not self.opts.read_only:
            caps.append(foxglove.CLIENT_PUBLISH)
        if self.clock.sim:
            caps.append(foxglove.CAPABILITY_TIME)
        return {
            "op": "serverInfo",
            "name": f"rostools bridge ({self.node.name})",
            "capabilities": caps,
            "supportedEncodings": ["ros1"],
            "metadata": {"ROS_DISTRO": "noetic", "ROS_MASTER_URI": self.node.master_uri},
            "sessionId": str(int(self.started * 1000)),
        }

    async def _drop(self, client: Client) -> None:
        """A client went away: its subscriptions, channels and parameter watches with it."""
        client.close()
        self.clients.discard(client)
        stats = client.stats
        if isinstance(client, RosbridgeClient):
            await self.rosbridge.forget_client(client)
        else:
            for sub_id in list(client.subscriptions):
                await self.ops.unsubscribe(client, sub_id)
            await self.ops.forget_client(client)
        self.event(
            "disconnected",
            client=client.name,
            messages=stats.messages,
            bytes=stats.bytes,
            dropped=stats.dropped,
        )

    # channels ----------------------------------------------------------------------------

    async def _graph_changed(self, change: GraphChange) -> None:
        for topic in change.removed_topics:
            await self._unadvertise(topic)
        for topic, type_name in change.added_topics.items():
            if not self.selection.wants(topic, type_name or None):
                continue
            if type_name and self.store.has_msg(type_name):
                try:
                    self._advertise(topic, TopicType.of(self.store, type_name))
                    continue
                except RostoolsError as err:  # a definition the store cannot complete
                    log.debug("%s: %s", type_name, err)
            self.spawn(self.links.open(topic, learning=True))
        for name in change.removed_services:
            service_id = self.service_ids.pop(name, None)
            if service_id is not None and self.services.pop(service_id, None) is not None:
                self.broadcast({"op": "unadvertiseServices", "serviceIds": [service_id]})
        for name in change.added_services:
            self.spawn(self._describe(name))
        if change.links_changed:
            self.ops.graph_changed(change.new)

    def _advertise(self, topic: str, topic_type: TopicType) -> None:
        channel = Channel(next(self.ids), topic, topic_type)
        self.channels[channel.id] = channel
        self.by_topic[topic] = channel
        self.broadcast({"op": "advertise", "channels": [channel.advertisement()]})
        self.event("advertised", topic=topic, type=topic_type.type)

    async def _unadvertise(self, topic: str) -> None:
        channel = self.by_topic.pop(topic, None)
        if channel is not None:
            del self.channels[channel.id]
            self.broadcast({"op": "unadvertise", "channelIds": [channel.id]})
            self.event("unadvertised", topic=topic)
        link = self.links.links.get(topic)
        if link is not None:
            for client, sub in list(link.readers.values()):
                client.unsubscribe(sub.id)
            link.readers.clear()
            link.learning = False
            await self.links.release(topic)

    def _learnt(self, topic: str, topic_type: TopicType) -> None:
        """A publisher's header gave the type (and definition) of ``topic``."""
        self.rosapi.learn(topic_type.type, topic_type.definition)
        link = self.links.links.get(topic)
        channel = self.by_topic.get(topic)
        if channel is None and topic in self.graph.graph.topics:
            self._advertise(topic, topic_type)
        elif channel is not None and channel.type.md5sum != topic_type.md5sum:
            # the store's definition is not the publisher's: the publisher's is the truth
            self.spawn(self._replace(topic, topic_type))
        if link is not None and link.learning:
            link.learning = False
            self.spawn(self.links.release(topic))

    async def _replace(self, topic: str, topic_type: TopicType) -> None:
        for client, _ in list(self.links.links[topic].readers.values()):
            client.status(
                foxglove.WARNING, f"{topic} is of another {topic_type.type}: subscribe again"
            )
        await self._unadvertise(topic)
        self._advertise(topic, topic_type)

    def _clock_frames(self, frames: list[Frame], conn: InboundConnection, now: float) -> None:
        self.links.feed("/clock", frames, conn)
        if now - self._last_time >= TIME_PERIOD and self.clock.last_ns:
            self._last_time = now
            self.broadcast(foxglove.time_message(self.clock.last_ns))

    # services ----------------------------------------------------------------------------

    async def _describe(self, name: str) -> None:
        found = await self.describer.describe(next(self.ids), name)
        if isinstance(found, str):
            self.event("service_skipped", service=name, reason=found)
            return
        if name not in self.graph.graph.services or name in self.service_ids:
            return  # gone meanwhile, or described twice
        self.services[found.id] = found
        self.service_ids[name] = found.id
        self.broadcast(self._services_message([found]))

    def _services_message(self, services: list[Service]) -> dict[str, Any]:
        return {
            "op": "advertiseServices",
            "services": [s.advertisement(self.store) for s in services],
        }


def _peer_name(address: Any) -> str:
    if isinstance(address, tuple) and len(address) >= 2:
        return f"{address[0]}:{address[1]}"
    return str(address)
