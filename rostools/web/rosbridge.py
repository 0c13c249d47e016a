"""rosbridge v2 clients of the bridge: their topics, status levels and fragments.

Subscribe, advertise and publish are here; service operations are ``rbservices.py``'s.

A client is answered as rosbridge_server 0.11.17 answers it, plus a ``status`` message for
everything refused (rosbridge only logs those), at the client's level (``set_level``;
``error`` at first). A client's subscriptions to one topic are one ROS-side reader, as in
rosbridge: the lowest throttle and queue length among them and the strongest compression.
Every message goes through the client's bounded queue (``client.Client``), so a slow client
costs only itself.
"""

from __future__ import annotations

import itertools
import logging
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING, Any

from rostools.errors import RostoolsError
from rostools.msgs import learnt
from rostools.msgs.codec import Codec
from rostools.msgs.rosbridge import RosbridgeFiller
from rostools.msgs.topictype import TopicType
from rostools.names import is_legal
from rostools.node.connection import Frame
from rostools.web.client import MAX_SUBSCRIPTIONS, QUEUE_MESSAGES, Rendered, Subscription
from rostools.web.rbclient import RosbridgeClient, TopicSubs
from rostools.web.rbencode import Encoders
from rostools.web.rbservices import RbServices
from rostools.wire import rosbridge as rb
from rostools.wire.rosbridge import ProtocolError, need

if TYPE_CHECKING:
    from rostools.web.state import BridgeState

log = logging.getLogger(__name__)


#: Seconds a new publisher keeps what a client publishes for subscribers still connecting
#: (rosbridge's PublisherConsistencyListener: 1 s).
EARLY = 1.0


class RosbridgeOps:
    """The rosbridge v2 operations of one bridge, for all its rosbridge clients."""

    def __init__(self, bridge: BridgeState, services: RbServices) -> None:
        self.bridge = bridge
        self.node = bridge.node
        self.services = services
        self.encoders = Encoders(bridge.store)
        self.sub_ids = itertools.count(1)
        #: topic -> rosbridge clients publishing on it (their advertisements, counted once each)
        self.publishing: dict[str, set[int]] = {}
        self.handlers: dict[str, Callable[[RosbridgeClient, dict[str, Any]], Any]] = {
            "subscribe": self.op_subscribe, "unsubscribe": self.op_unsubscribe,
            "advertise": self.op_advertise, "unadvertise": self.op_unadvertise,
            "publish": self.op_publish, "set_level": self.op_set_level,
            "fragment": self.op_fragment, "call_service": services.op_call_service,
            "service_response": services.op_service_response,
            "advertise_service": services.op_advertise_service,
            "unadvertise_service": services.op_unadvertise_service,
        }  # fmt: skip

    async def handle(self, client: RosbridgeClient, message: str | bytes) -> None:
        """One message from ``client``."""
        ident = None
        try:
            if not isinstance(message, str):
                raise ProtocolError("binary messages are not understood: send JSON text")
            request = rb.parse(message)
            ident = request.get("id")
            handler = self.handlers.get(request["op"])
            if handler is None:
                raise ProtocolError(
                    f"unknown op {request['op']!r}: allowed are {', '.join(self.handlers)}", ident
                )
            size = request.get("fragment_size")
            if isinstance(size, int) and not isinstance(size, bool):
                client.fragment_size = size
            await handler(client, request)
        except ProtocolError as err:
            self.refuse(client, str(err), ident if err.ident is None else err.ident, err.level)
        except (RostoolsError, ValueError, TypeError, KeyError) as err:
            # a case no check foresaw: this op fails, the client and the bridge go on
            log.warning("rosbridge client %s: %r", client.name, err, exc_info=True)
            self.refuse(client, f"the op failed: {type(err).__name__}: {err}", ident)

    def refuse(
        self, client: RosbridgeClient, text: str, ident: Any = None, level: str = "error"
    ) -> None:
        """Tell ``client`` (at its level) and the terminal."""
        client.tell(level, text, ident)
        self.bridge.event("refused", client=client.name, reason=text)

    async def op_set_level(self, client: RosbridgeClient, request: dict[str, Any]) -> None:
        """The least level of status the client hears."""
        level = need(request, "level", str)
        if level not in rb.LEVELS:
            raise ProtocolError(f"set_level: {level!r} is not one of {', '.join(rb.LEVELS)}")
        client.level = level

    async def op_fragment(self, client: RosbridgeClient, request: dict[str, Any]) -> None:
        """A part of a bigger message; the whole is handled once every part is in."""
        whole = client.fragments.add(request)
        if whole is not None:
            await self.handle(client, whole)

    # subscriptions -----------------------------------------------------------------------

    async def op_subscribe(self, client: RosbridgeClient, request: dict[str, Any]) -> None:
        """Subscribe; the topic's first reader subscribes the node to it."""
        topic = self._topic(request)
        asked_type = need(request, "type", str, required=False)
        ask = {
            "throttle_rate": need(request, "throttle_rate", int, required=False) or 0,
            "queue_length": need(request, "queue_length", int, required=False) or 0,
            "compression": need(request, "compression", str, required=False) or "none",
        }
        if ask["compression"] not in rb.COMPRESSIONS:
            raise ProtocolError(
                f"subscribe: compression {ask['compression']!r} is not one of "
                f"{', '.join(rb.COMPRESSIONS)}"
            )
        known = self.known_type(topic)
        if asked_type:
            if known is not None and known.type != asked_type:
                raise ProtocolError(f"subscribe: {topic} is of type {known.type}, not {asked_type}")
            if known is None and not self.bridge.store.has_msg(asked_type):
                raise ProtocolError(f"subscribe: {topic}: no message type {asked_type} is known")
        elif known is None and ask["compression"] != "cbor-raw" and not await self._on_graph(topic):
            raise ProtocolError(
                f"subscribe: {topic} is not on the graph yet: give its type to subscribe before"
            )
        subs = client.topics.get(topic)
        if subs is None:
            if len(client.topics) >= MAX_SUBSCRIPTIONS:
                raise ProtocolError(f"subscribe: more than {MAX_SUBSCRIPTIONS} topics")
            sub = Subscription(next(self.sub_ids), 0, topic)
            subs = client.topics[topic] = TopicSubs(topic, sub)
            client.subscriptions[sub.id] = sub
        subs.asks[request.get("id")] = {**ask, "type": asked_type}
        self._apply(client, subs)
        try:
            link = await self.bridge.links.open(topic)
        except RostoolsError as err:
            await self._drop_topic(client, topic)
            raise ProtocolError(f"subscribe: {topic}: {err}") from None
        if client.topics.get(topic) is not subs:
            return  # unsubscribed, or gone, meanwhile
        sub = subs.sub
        if (id(client), sub.id) not in link.readers:
            link.readers[(id(client), sub.id)] = (client, sub)
            stamp, now = self.bridge.clock.now(), self.bridge.links.clock()
            for frame in list(link.latched.values()):
                sub.last_taken = 0.0  # each latched message is sent, however throttled
                client.offer(sub, stamp, frame, now)
            self.bridge.event("subscribed", client=client.name, topic=topic)

    async def _on_graph(self, topic: str) -> bool:
        """Whether ``topic`` is on the graph: at the last look, or the master's now."""
        if topic in self.bridge.current_graph().topics:
            return True
        try:
            return topic in await self.node.master.topic_types()
        except RostoolsError:
            return False

    def _apply(self, client: RosbridgeClient, subs: TopicSubs) -> None:
        """The queue's settings from every subscription to the topic."""
        asks = list(subs.asks.values())
        sub = subs.sub
        throttle = min(a["throttle_rate"] for a in asks) / 1000.0
        limit = min(a["queue_length"] for a in asks)
        most = self.bridge.opts.max_rates.get(subs.topic)
        sub.interval = max(throttle, 1.0 / most if most else 0.0)
        sub.limit = limit if limit > 0 else QUEUE_MESSAGES
        asked_types = [a["type"] for a in asks if a["type"]]
        sub.render = self._renderer(client, subs.topic, subs.compression, asked_types)

    def _renderer(
        self, client: RosbridgeClient, topic: str, compression: str, asked: list[str]
    ) -> Callable[[int, Frame], Sequence[Rendered]]:
        def render(stamp: int, frame: Frame) -> Sequence[Rendered]:
            topic_type = None
            if compression != "cbor-raw":
                topic_type = self.known_type(topic)
                if topic_type is None and asked:
                    topic_type = TopicType.of(self.bridge.store, asked[0])
            out = self.encoders.encode(topic, topic_type, compression, stamp, frame)
            return client.cut(out) if isinstance(out, str) else (out,)

        return render

    def known_type(self, topic: str) -> TopicType | None:
        """The type of ``topic``: its publisher's, else its channel's, else None."""
        link = self.bridge.links.links.get(topic)
        if link is not None and link.type is not None:
            return link.type
        channel = self.bridge.by_topic.get(topic)
        return channel.type if channel is not None else None

    async def op_unsubscribe(self, client: RosbridgeClient, request: dict[str, Any]) -> None:
        """End the subscription of that id (no id: every one to the topic)."""
        topic = self._topic(request)
        subs = client.topics.get(topic)
        if subs is None:
            return  # rosbridge says nothing either
        ident = request.get("id")
        if ident is None:
            subs.asks.clear()
        else:
            subs.asks.pop(ident, None)
        if subs.asks:
            self._apply(client, subs)
        else:
            await self._drop_topic(client, topic)

    async def _drop_topic(self, client: RosbridgeClient, topic: str) -> None:
        subs = client.topics.pop(topic, None)
        if subs is None:
            return
        client.unsubscribe(subs.sub.id)
        link = self.bridge.links.links.get(topic)
        if link is not None:
            link.readers.pop((id(client), subs.sub.id), None)
            if not link.readers:
                self.encoders.forget(topic)
            await self.bridge.links.release(topic)
        self.bridge.event("unsubscribed", client=client.name, topic=topic)

    # publishing --------------------------------------------------------------------------

    async def op_advertise(self, client: RosbridgeClient, request: dict[str, Any]) -> None:
        """Publish ``topic`` as ``type`` on the graph, for this client."""
        topic = self._topic(request)
        type_name = need(request, "type", str)
        self._writable("advertise")
        try:
            topic_type = TopicType.of(self.bridge.store, type_name)
        except RostoolsError:
            known = self.known_type(topic)
            if known is None or known.type != type_name:
                raise ProtocolError(
                    f"advertise: {topic}: no message type {type_name} is known"
                ) from None
            topic_type = known
        await self._publisher(client, topic, topic_type, request)
        client.advertised.setdefault(topic, set()).add(request.get("id"))

    async def _publisher(
        self, client: RosbridgeClient, topic: str, topic_type: TopicType, request: dict[str, Any]
    ) -> None:
        current = self.node.publishers.get(topic)
        if current is not None and current.type.md5sum != topic_type.md5sum:
            raise ProtocolError(
                f"{request['op']}: {topic} is published as {current.type.type} here, "
                f"not {topic_type.type}"
            )
        latch = request.get("latch") is True
        queue_size = request.get("queue_size")
        size = queue_size if isinstance(queue_size, int) and queue_size > 0 else 100
        pub = await self.node.advertise(topic, topic_type, latch=latch, queue_size=size)
        if current is None:
            pub.keep_early(EARLY)
        if id(client) not in self.publishing.setdefault(topic, set()):
            self.publishing[topic].add(id(client))
            self.bridge.event(
                "client_advertised", client=client.name, topic=topic, type=topic_type.type
            )

    async def op_unadvertise(self, client: RosbridgeClient, request: dict[str, Any]) -> None:
        """The advertisement of that id ends; the client's last one ends its publishing."""
        topic = self._topic(request)
        ids = client.advertised.get(topic)
        if ids is None:
            raise ProtocolError(
                f"unadvertise: {topic} is not advertised by this client", level="warning"
            )
        ident = request.get("id")
        if ident is None:
            ids.clear()
        else:
            ids.discard(ident)
        if not ids:
            del client.advertised[topic]
            await self._stop_publishing(client, topic)

    async def _stop_publishing(self, client: RosbridgeClient, topic: str) -> None:
        clients = self.publishing.get(topic, set())
        clients.discard(id(client))
        if not clients:
            self.publishing.pop(topic, None)
            try:
                await self.node.unadvertise(topic)
            except RostoolsError as err:
                self.bridge.event("warning", message=f"unadvertising {topic}: {err}")

    async def op_publish(self, client: RosbridgeClient, request: dict[str, Any]) -> None:
        """One message on ``topic``; a topic not advertised yet is, with the graph's type."""
        topic = self._topic(request)
        self._writable("publish")
        values = request.get("msg", {})
        pub = self.node.publishers.get(topic)
        if topic not in client.advertised:
            topic_type = pub.type if pub is not None else self.known_type(topic)
            if topic_type is None:
                raise ProtocolError(
                    f"publish: {topic} is not advertised, and its type is not known: "
                    "advertise it first"
                )
            await self._publisher(client, topic, topic_type, request)
            client.advertised[topic] = {None}
            pub = self.node.publishers[topic]
        if pub is None:
            raise ProtocolError(f"publish: {topic} is no longer advertised")
        try:
            msg = RosbridgeFiller(self.codec(pub.type)).message(pub.type.type, values)
            data = self.codec(pub.type).serialize(msg)
        except RostoolsError as err:
            raise ProtocolError(f"publish: {topic}: {err}") from None
        pub.publish(data)

    def codec(self, topic_type: TopicType) -> Codec:
        """The codec of ``topic_type`` as it is defined (the store's or a publisher's)."""
        return learnt.codec(
            self.bridge.store, topic_type.type, topic_type.md5sum, topic_type.definition
        )

    def _writable(self, op: str) -> None:
        if self.bridge.opts.read_only:
            raise ProtocolError(f"{op}: this bridge is read-only (--read-only)")

    def _topic(self, request: dict[str, Any]) -> str:
        name = need(request, "topic", str)
        if not name or not is_legal(name):
            raise ProtocolError(f"{request['op']}: {name!r} is not a legal topic name")
        return self.node.resolve(name)

    # a client that leaves ----------------------------------------------------------------

    async def forget_client(self, client: RosbridgeClient) -> None:
        """Everything a client that left had set up."""
        for topic in list(client.topics):
            await self._drop_topic(client, topic)
        for topic in list(client.advertised):
            await self._stop_publishing(client, topic)
        client.advertised.clear()
        await self.services.forget_client(client)
