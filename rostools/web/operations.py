"""What a client may ask of the bridge, each operation checked before it acts.

Anything refused (a message that is not the protocol, an unknown channel, a publish on a
channel the client did not advertise, a flood of subscriptions) is answered with a ``status``
message to that client alone, naming the problem; nothing else happens.
"""

from __future__ import annotations

from collections import Counter
from typing import TYPE_CHECKING, Any

from rostools.errors import NotFoundError, RostoolsError
from rostools.msgs.store import md5_of
from rostools.msgs.topictype import TopicType
from rostools.names import is_legal
from rostools.web import params
from rostools.web.client import MAX_SUBSCRIPTIONS, Client, Subscription
from rostools.wire import foxglove
from rostools.wire.foxglove import ERROR, WARNING, CallRequest, ClientData, ProtocolError, field

if TYPE_CHECKING:
    from rostools.web.graph import Graph
    from rostools.web.state import BridgeState

#: Service calls one client may have in flight.
MAX_CALLS = 64


class Operations:
    """The handlers of every client operation, for one bridge."""

    def __init__(self, bridge: BridgeState) -> None:
        self.bridge = bridge
        self.node = bridge.node
        #: topic -> clients' channels publishing on it
        self.publishing: Counter[str] = Counter()
        #: parameter -> clients following it
        self.following: Counter[str] = Counter()
        self.calls: Counter[int] = Counter()  # in flight, by client
        self._last_graph: Graph | None = None
        self.node.on_param_update = self._param_update

    async def handle(self, client: Client, message: str | bytes) -> None:
        """One message from ``client``."""
        try:
            if isinstance(message, str):
                request = foxglove.parse_json(message)
                await getattr(self, "op_" + request["op"])(client, request)
            else:
                data = foxglove.parse_binary(message)
                if isinstance(data, ClientData):
                    self._publish(client, data)
                else:
                    self._call(client, data)
        except ProtocolError as err:
            self.refuse(client, str(err))

    def refuse(self, client: Client, reason: str, level: int = ERROR) -> None:
        """Answer ``client`` with a status, and tell the terminal."""
        client.status(level, reason)
        self.bridge.event("refused", client=client.name, reason=reason)

    # subscriptions -----------------------------------------------------------------------

    async def op_subscribe(self, client: Client, request: dict[str, Any]) -> None:
        """Subscribe to channels; a topic's first reader subscribes the node to it."""
        for item in request["subscriptions"]:
            sub_id = field(item, "id", int, "subscribe")
            channel = self.bridge.channels.get(field(item, "channelId", int, "subscribe"))
            if channel is None:
                self.refuse(client, f"subscribe: no channel {item['channelId']}", WARNING)
                continue
            if sub_id in client.subscriptions:
                self.refuse(client, f"subscribe: subscription id {sub_id} is in use")
                continue
            if len(client.subscriptions) >= MAX_SUBSCRIPTIONS:
                self.refuse(client, f"subscribe: more than {MAX_SUBSCRIPTIONS} subscriptions")
                return
            sub = Subscription(
                sub_id, channel.id, channel.topic, self._interval(item, channel.topic)
            )
            client.subscriptions[sub_id] = sub
            try:
                link = await self.bridge.links.open(channel.topic)
            except RostoolsError as err:
                client.unsubscribe(sub_id)
                self.refuse(client, f"subscribe: {channel.topic}: {err}")
                continue
            if client.subscriptions.get(sub_id) is not sub:
                continue  # the client left, or unsubscribed, meanwhile
            link.readers[(id(client), sub_id)] = (client, sub)
            stamp, now = self.bridge.clock.now(), self.bridge.links.clock()
            for frame in list(link.latched.values()):
                sub.last_taken = 0.0  # each latched message is sent, however throttled
                client.offer(sub, stamp, frame, now)
            self.bridge.event("subscribed", client=client.name, topic=channel.topic)

    def _interval(self, item: dict[str, Any], topic: str) -> float:
        """The least time between two messages: the bridge's limit or the client's."""
        rates = [self.bridge.opts.max_rates[topic]] if topic in self.bridge.opts.max_rates else []
        asked = item.get("maxRate")
        if isinstance(asked, int | float) and not isinstance(asked, bool) and asked > 0:
            rates.append(float(asked))
        return 1.0 / min(rates) if rates else 0.0

    async def op_unsubscribe(self, client: Client, request: dict[str, Any]) -> None:
        """Unsubscribe; a topic's last reader lets the node go of it."""
        for sub_id in foxglove.ids(request["subscriptionIds"], "unsubscribe"):
            if sub_id not in client.subscriptions:
                self.refuse(client, f"unsubscribe: no subscription {sub_id}", WARNING)
                continue
            await self.unsubscribe(client, sub_id)

    async def unsubscribe(self, client: Client, sub_id: int) -> None:
        """End one subscription of ``client``."""
        sub = client.unsubscribe(sub_id)
        if sub is None:
            return
        link = self.bridge.links.links.get(sub.topic)
        if link is not None:
            link.readers.pop((id(client), sub_id), None)
            await self.bridge.links.release(sub.topic)
        self.bridge.event("unsubscribed", client=client.name, topic=sub.topic)

    # client publish ----------------------------------------------------------------------

    async def op_advertise(self, client: Client, request: dict[str, Any]) -> None:
        """A client's channels: each becomes a publisher on the graph, of the client's type."""
        if self.bridge.opts.read_only:
            self.refuse(client, "advertise: this bridge is read-only (--read-only)")
            return
        for item in request["channels"]:
            channel_id = field(item, "id", int, "advertise")
            topic = field(item, "topic", str, "advertise")
            name = field(item, "schemaName", str, "advertise")
            if item.get("encoding") != "ros1":
                self.refuse(
                    client, f"advertise: {topic}: encoding {item.get('encoding')!r}, not ros1"
                )
                continue
            if channel_id in client.channels:
                self.refuse(client, f"advertise: channel id {channel_id} is in use")
                continue
            topic = self.node.resolve(topic) if topic and is_legal(topic) else ""
            if not topic:
                self.refuse(client, f"advertise: {item['topic']!r} is not a legal topic name")
                continue
            topic_type = self._client_type(name, item.get("schema"))
            if isinstance(topic_type, str):
                self.refuse(client, f"advertise: {topic}: {topic_type}")
                continue
            current = self.node.publishers.get(topic)
            if current is not None and current.type.md5sum != topic_type.md5sum:
                self.refuse(client, f"advertise: {topic} is published as {current.type.type} here")
                continue
            await self.node.advertise(topic, topic_type)
            client.channels[channel_id] = topic
            self.publishing[topic] += 1
            self.bridge.event("client_advertised", client=client.name, topic=topic, type=name)

    def _client_type(self, name: str, schema: Any) -> TopicType | str:
        """The type a client publishes: its schema, else the store's; or why not."""
        if isinstance(schema, str) and schema.strip():
            md5 = md5_of(name, schema)
            if not md5:
                return f"the schema of {name} does not read as a ROS 1 definition"
            header = {"type": name, "md5sum": md5, "message_definition": schema}
            return TopicType.from_header(header, self.bridge.store)
        try:
            return TopicType.of(self.bridge.store, name)
        except RostoolsError as err:
            return f"no schema given, and {err}"

    async def op_unadvertise(self, client: Client, request: dict[str, Any]) -> None:
        """A client stops publishing on its channels."""
        for channel_id in foxglove.ids(request["channelIds"], "unadvertise"):
            if channel_id not in client.channels:
                self.refuse(client, f"unadvertise: no channel {channel_id} of this client", WARNING)
                continue
            await self._stop_publishing(client.channels.pop(channel_id))

    async def _stop_publishing(self, topic: str) -> None:
        self.publishing[topic] -= 1
        if self.publishing[topic] <= 0:
            del self.publishing[topic]
            try:
                await self.node.unadvertise(topic)
            except RostoolsError as err:
                self.bridge.event("warning", message=f"unadvertising {topic}: {err}")

    def _publish(self, client: Client, data: ClientData) -> None:
        topic = client.channels.get(data.channel)
        if topic is None:
            self.refuse(
                client, f"publish on channel {data.channel}, which this client did not advertise"
            )
            return
        self.node.publishers[topic].publish(bytes(data.payload))

    # services ----------------------------------------------------------------------------

    def _call(self, client: Client, request: CallRequest) -> None:
        service = self.bridge.services.get(request.service)
        reason = ""
        if self.bridge.opts.read_only:
            reason = "this bridge is read-only (--read-only)"
        elif service is None:
            reason = f"no service {request.service}"
        elif request.encoding != "ros1":
            reason = f"encoding {request.encoding!r}: this bridge speaks ros1"
        elif self.calls[id(client)] >= MAX_CALLS:
            reason = f"more than {MAX_CALLS} calls in flight"
        if reason or service is None:
            self._failed(client, request, reason)
            return
        self.calls[id(client)] += 1
        self.bridge.spawn(self._run_call(client, request, bytes(request.payload)))

    async def _run_call(self, client: Client, request: CallRequest, payload: bytes) -> None:
        service = self.bridge.services.get(request.service)
        try:
            if service is None:
                raise RostoolsError("the service went away")
            response = await self.bridge.describer.call(service, payload)
        except RostoolsError as err:
            self._failed(client, request, str(err))
        else:
            client.send(foxglove.service_response(request.service, request.call, "ros1", response))
        finally:
            self.calls[id(client)] -= 1

    def _failed(self, client: Client, request: CallRequest, reason: str) -> None:
        client.send(
            {
                "op": "serviceCallFailure",
                "serviceId": request.service,
                "callId": request.call,
                "message": reason,
            }
        )
        self.bridge.event("refused", client=client.name, reason=f"service call: {reason}")

    # parameters --------------------------------------------------------------------------

    async def op_getParameters(self, client: Client, request: dict[str, Any]) -> None:  # noqa: N802
        """Parameters by name; none named: all of them."""
        names = [n for n in request["parameterNames"] if isinstance(n, str)]
        found: list[dict[str, Any]] = []
        try:
            if not names:
                tree = await self.node.master.get_param("/")
                found = [params.to_client(k, v) for k, v in params.leaves("/", tree)]
            for name in names:
                key = name if name.startswith("/") else "/" + name
                try:
                    found.append(params.to_client(name, await self.node.master.get_param(key)))
                except NotFoundError:
                    continue
        except RostoolsError as err:
            self.refuse(client, f"getParameters: {err}")
            return
        self._values(client, found, request.get("id"))

    async def op_setParameters(self, client: Client, request: dict[str, Any]) -> None:  # noqa: N802
        """Set parameters; with an ``id``, the new values are sent back."""
        if self.bridge.opts.read_only:
            self.refuse(client, "setParameters: this bridge is read-only (--read-only)")
            return
        done: list[dict[str, Any]] = []
        for item in request["parameters"]:
            name, value = params.from_client(item)
            try:
                await self.node.master.set_param(name, value)
            except RostoolsError as err:
                self.refuse(client, f"setParameters: {name}: {err}")
                continue
            done.append(params.to_client(item["name"], value))
        if request.get("id") is not None:
            self._values(client, done, request.get("id"))

    def _values(self, client: Client, found: list[dict[str, Any]], ident: Any) -> None:
        message: dict[str, Any] = {"op": "parameterValues", "parameters": found}
        if isinstance(ident, str):
            message["id"] = ident
        client.send(message)

    async def op_subscribeParameterUpdates(self, client: Client, request: dict[str, Any]) -> None:  # noqa: N802
        """Follow parameters: the master tells the node of each change (``paramUpdate``)."""
        for name in request["parameterNames"]:
            if not isinstance(name, str) or name in client.parameters:
                continue
            key = name if name.startswith("/") else "/" + name
            if not self.following[key]:
                try:
                    await self.node.master.call("subscribeParam", self.node.uri, key)
                except RostoolsError as err:
                    self.refuse(client, f"subscribeParameterUpdates: {name}: {err}")
                    continue
            self.following[key] += 1
            client.parameters.add(key)

    async def op_unsubscribeParameterUpdates(self, client: Client, request: dict[str, Any]) -> None:  # noqa: N802
        """Stop following parameters."""
        for name in request["parameterNames"]:
            key = name if isinstance(name, str) and name.startswith("/") else f"/{name}"
            if key in client.parameters:
                client.parameters.discard(key)
                await self._unfollow(key)

    async def _unfollow(self, key: str) -> None:
        self.following[key] -= 1
        if self.following[key] <= 0:
            del self.following[key]
            try:
                await self.node.master.call("unsubscribeParam", self.node.uri, key)
            except RostoolsError as err:
                self.bridge.event("warning", message=f"unsubscribeParam {key}: {err}")

    def _param_update(self, key: str, value: Any) -> None:
        key = "/" + key.strip("/")
        for client in self.bridge.clients:
            for name in client.parameters:
                if name == key or name.startswith(key + "/"):
                    sub = _under(value, name[len(key) :])
                    values = [params.to_client(name, sub)] if sub is not None else [{"name": name}]
                elif key.startswith(name + "/"):
                    values = [params.to_client(key, value)]
                else:
                    continue
                client.send({"op": "parameterValues", "parameters": values})

    # the connection graph ----------------------------------------------------------------

    async def op_subscribeConnectionGraph(self, client: Client, request: dict[str, Any]) -> None:  # noqa: N802
        """Follow who publishes, subscribes and serves what."""
        client.graph = True
        client.send(_graph_update(self.bridge.current_graph(), None))

    async def op_unsubscribeConnectionGraph(self, client: Client, request: dict[str, Any]) -> None:  # noqa: N802
        """Stop following the connection graph."""
        client.graph = False

    def graph_changed(self, graph: Graph) -> None:
        """Tell the clients that follow the connection graph."""
        update = _graph_update(graph, self._last_graph)
        self._last_graph = graph
        for client in self.bridge.clients:
            if client.graph:
                client.send(update)

    async def op_fetchAsset(self, client: Client, request: dict[str, Any]) -> None:  # noqa: N802
        """Assets are not offered (the capability is not announced)."""
        self.refuse(client, "fetchAsset: this bridge serves no assets")

    async def forget_client(self, client: Client) -> None:
        """What a client that left had set up: its channels and parameter watches."""
        for topic in list(client.channels.values()):
            await self._stop_publishing(topic)
        client.channels.clear()
        for key in list(client.parameters):
            await self._unfollow(key)
        client.parameters.clear()
        self.calls.pop(id(client), None)


def _under(value: Any, path: str) -> Any:
    """The part of a parameter tree at ``path`` (``/a/b``), or None."""
    for part in filter(None, path.split("/")):
        if not isinstance(value, dict) or part not in value:
            return None
        value = value[part]
    if value == {}:
        return None  # the master sends an empty tree for a deleted parameter
    return value


def _graph_update(graph: Graph, before: Graph | None) -> dict[str, Any]:
    removed_topics = set()
    removed_services: list[str] = []
    if before is not None:
        removed_topics = (set(before.publishers) | set(before.subscribers)) - (
            set(graph.publishers) | set(graph.subscribers)
        )
        removed_services = sorted(set(before.services) - set(graph.services))
    return {
        "op": "connectionGraphUpdate",
        "publishedTopics": [{"name": t, "publisherIds": n} for t, n in graph.publishers.items()],
        "subscribedTopics": [{"name": t, "subscriberIds": n} for t, n in graph.subscribers.items()],
        "advertisedServices": [{"name": s, "providerIds": n} for s, n in graph.services.items()],
        "removedTopics": sorted(removed_topics),
        "removedServices": removed_services,
    }
