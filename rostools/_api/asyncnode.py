"""``AsyncNode``: the API's one implementation of a node, on asyncio.

It wraps ``rostools.node.node.LiveNode`` (the node every command runs) and adds what a script
wants: typed messages in and out, several subscriptions to one topic, waiting for a message,
service calls and servers, parameters. The blocking ``rostools.Node`` runs this on a background
loop.
"""

from __future__ import annotations

import asyncio
import collections
import inspect
import logging
import os
import time
from collections.abc import AsyncIterator, Awaitable, Callable, Coroutine
from types import TracebackType
from typing import Any

from rostools._api import exiting, messages
from rostools._api.messages import Values
from rostools.errors import (
    NotFoundError,
    RostoolsError,
    ServiceError,
    TimeoutExpired,
    UsageError,
    one_line,
)
from rostools.msgs.codec import DecodeError
from rostools.msgs.message import Message
from rostools.msgs.topictype import ServiceType
from rostools.node.connection import Frame, InboundConnection
from rostools.node.node import LiveNode
from rostools.node.notice import Notice
from rostools.node.publisher import TopicPublisher as CorePublisher
from rostools.node.service import ServiceClient, ServiceServer
from rostools.node.subscriber import Subscriber as CoreSubscriber
from rostools.rosgraph.masterapi import SERVICE_TIMEOUT

log = logging.getLogger("rostools")

#: The ROS default when ``ROS_MASTER_URI`` is not set.
DEFAULT_MASTER_URI = "http://localhost:11311/"
#: Messages a subscription without a callback keeps for its reader; the oldest go first.
QUEUE_SIZE = 1000
#: How often waits that poll (subscribers, services) look again.
POLL = 0.01

Callback = Callable[[Message], Any]
RawCallback = Callable[[bytes, dict[str, str], float], None]


def default_master_uri() -> str:
    """``ROS_MASTER_URI``, or the ROS default."""
    return os.environ.get("ROS_MASTER_URI") or DEFAULT_MASTER_URI


def _warn(notice: Notice) -> None:
    log.warning("%s", one_line(notice.message))


class AsyncSubscription:
    """Messages of one topic: ``async for msg in sub``, ``await sub.get()``, or a callback."""

    def __init__(
        self,
        topic: _Topic,
        msg_type: str | None,
        callback: Callback | None,
        queue_size: int = QUEUE_SIZE,
    ) -> None:
        self._topic = topic
        self.topic = topic.name
        #: The type asked for; None takes whatever the publishers send.
        self.msg_type = msg_type
        self.callback = callback
        self.queue: collections.deque[Message] = collections.deque(maxlen=queue_size)
        self._arrived = asyncio.Event()
        self.closed = False
        #: Messages received (including those a callback took).
        self.count = 0
        #: The last message received.
        self.last: Message | None = None
        self._mismatch_told = False

    def deliver(self, msg: Message) -> None:
        """A message arrived (on the loop)."""
        if self.msg_type is not None and msg._type != self.msg_type:
            if not self._mismatch_told:
                self._mismatch_told = True
                log.warning(
                    "%s carries %s, not %s: its messages are left out",
                    self.topic,
                    one_line(msg._type),  # the publisher's word
                    self.msg_type,
                )
            return
        self.count += 1
        self.last = msg
        if self.callback is None:
            self.queue.append(msg)
            self._arrived.set()
            return
        try:
            result = self.callback(msg)
            if inspect.isawaitable(result):
                asyncio.ensure_future(result).add_done_callback(_log_failure)
        except Exception:
            log.exception("subscriber callback on %s failed", self.topic)

    async def get(self, timeout: float | None = None) -> Message:
        """The next message (oldest first); ``TimeoutExpired`` after ``timeout`` seconds."""
        deadline = None if timeout is None else time.monotonic() + timeout
        while not self.queue:
            if self.closed:
                raise UsageError(f"the subscription to {self.topic} is closed")
            self._arrived.clear()
            left = None if deadline is None else deadline - time.monotonic()
            if left is not None and left <= 0:
                raise TimeoutExpired(f"no message on {self.topic} within {timeout:g} s")
            try:
                await asyncio.wait_for(self._arrived.wait(), left)
            except asyncio.TimeoutError:
                continue
        return self.queue.popleft()

    def __aiter__(self) -> AsyncIterator[Message]:
        return self._iterate()

    async def _iterate(self) -> AsyncIterator[Message]:
        while not self.closed or self.queue:
            try:
                yield await self.get()
            except UsageError:
                return

    async def close(self) -> None:
        """Stop receiving; the last subscription to a topic unsubscribes the node."""
        if not self.closed:
            self.closed = True
            self._arrived.set()
            await self._topic.remove(self)

    async def __aenter__(self) -> AsyncSubscription:
        return self

    async def __aexit__(
        self, kind: type[BaseException] | None, err: BaseException | None, tb: TracebackType | None
    ) -> None:
        await self.close()


def _log_failure(task: asyncio.Future[Any]) -> None:
    if not task.cancelled() and task.exception() is not None:
        log.error("subscriber callback failed: %r", task.exception())


class _Topic:
    """One ``rostools.node`` subscriber shared by every subscription of a node to a topic."""

    def __init__(self, node: AsyncNode, name: str) -> None:
        self.node = node
        self.name = name
        self.listeners: list[AsyncSubscription] = []
        self.raw: list[RawCallback] = []
        self.core: CoreSubscriber | None = None
        #: The last message's bytes and its publisher's header (decoded when asked for).
        self.last: tuple[bytes, dict[str, str]] | None = None
        self.count = 0

    async def start(self) -> None:
        self.core = await self.node.core.subscribe(self.name, self.on_frames)

    def on_frames(self, frames: list[Frame], conn: InboundConnection, now: float) -> None:
        header = conn.header or {}
        for raw in self.raw:
            for frame in frames:
                raw(bytes(frame), header, now)
        decode = None
        for frame in frames:
            data = bytes(frame)
            self.count += 1
            self.last = (data, header)
            if not self.listeners:
                continue
            if decode is None:
                try:
                    decode = messages.decoder(
                        header.get("type", ""), header.get("md5sum", ""),
                        header.get("message_definition", ""),
                    )  # fmt: skip
                except RostoolsError as err:
                    log.warning("cannot decode %s: %s", self.name, one_line(err))
                    return
            try:
                msg = decode(data)
            except Exception as err:  # noqa: BLE001 - one bad message, not the subscription
                log.warning("a message on %s does not decode: %s", self.name, one_line(err))
                continue
            for listener in list(self.listeners):
                listener.deliver(msg)

    def last_message(self) -> Message | bytes | None:
        """The last message received, decoded if its type can be."""
        if self.last is None:
            return None
        data, header = self.last
        try:
            return messages.decoder(
                header.get("type", ""), header.get("md5sum", ""),
                header.get("message_definition", ""),
            )(data)  # fmt: skip
        except Exception:  # noqa: BLE001 - a report shows the bytes then
            return data

    async def remove(self, listener: AsyncSubscription | RawCallback) -> None:
        if isinstance(listener, AsyncSubscription):
            if listener in self.listeners:
                self.listeners.remove(listener)
        elif listener in self.raw:
            self.raw.remove(listener)
        if not self.listeners and not self.raw:
            await self.node._unsubscribe(self)


class AsyncPublisher:
    """Publishes typed messages on one topic."""

    def __init__(self, core: CorePublisher) -> None:
        self.core = core
        self.topic = core.topic
        self.msg_type = core.type.type

    @property
    def subscriber_count(self) -> int:
        """How many subscribers are connected now."""
        return self.core.subscriber_count

    def serialize(self, msg: Values) -> bytes:
        """The wire bytes of ``msg`` (a message, dict, list or YAML), checked against the type."""
        return messages.message(self.msg_type, msg).serialize()

    def publish(self, msg: Values = None, /, **fields: Any) -> None:
        """Send a message (a message object, dict, list, YAML text, or field keywords).

        The message is built and checked here, so a bad value raises in the caller.
        """
        data = messages.message(self.msg_type, msg, **fields).serialize()
        self.core.publish(data)

    async def wait_for_subscribers(self, count: int = 1, timeout: float | None = None) -> None:
        """Until ``count`` subscribers are connected; ``TimeoutExpired`` after ``timeout``."""
        await _until(
            lambda: self.core.subscriber_count >= count,
            timeout,
            f"{count} subscriber(s) on {self.topic}",
        )


async def _until(condition: Callable[[], bool], timeout: float | None, what: str) -> None:
    deadline = None if timeout is None else time.monotonic() + timeout
    while not condition():
        if deadline is not None and time.monotonic() >= deadline:
            raise TimeoutExpired(f"no {what} within {timeout:g} s")
        await asyncio.sleep(POLL)


class AsyncNode:
    """A ROS node for asyncio code: ``async with AsyncNode("name") as node: ...``.

    ``name`` is made unique with a suffix unless ``anonymous`` is false. ``master_uri``
    defaults to ``ROS_MASTER_URI``.
    """

    def __init__(
        self,
        name: str = "rostools_api",
        master_uri: str | None = None,
        *,
        anonymous: bool = True,
        namespace: str | None = None,
    ) -> None:
        self.core = LiveNode(
            name, master_uri or default_master_uri(), anonymous_name=anonymous, ns=namespace
        )
        self.core.notify = _warn
        self._topics: dict[str, _Topic] = {}
        self._clients: dict[str, ServiceClient] = {}
        self.started = False
        self.closed = False
        self._closing: asyncio.Future[None] | None = None

    @property
    def name(self) -> str:
        """The node's full name."""
        return self.core.name

    @property
    def master_uri(self) -> str:
        """The master this node registers with."""
        return self.core.master_uri

    @property
    def uri(self) -> str:
        """The node's slave API URI."""
        return self.core.uri

    async def start(self) -> AsyncNode:
        """Open the node's sockets (registration happens as it publishes and subscribes)."""
        if not self.started:
            try:
                await self.core.start()
            except OSError as err:
                raise RostoolsError(
                    f"cannot open the node's sockets: {err.strerror or err}"
                ) from err
            self.started = True
            exiting.track(self.core, self.close)
        return self

    async def close(self) -> None:
        """Unregister everything and close every connection; only the first close does it."""
        # A close while another is under way (the process's end meets the script's) waits
        # for that one.
        if self.started and self._closing is None:
            self.closed = True
            self._closing = asyncio.ensure_future(self._close())
        if self._closing is not None:
            await asyncio.shield(self._closing)

    async def _close(self) -> None:
        try:
            for client in self._clients.values():
                client.close()
            await self.core.close()
        finally:
            exiting.forget(self.core)

    async def __aenter__(self) -> AsyncNode:
        return await self.start()

    async def __aexit__(
        self, kind: type[BaseException] | None, err: BaseException | None, tb: TracebackType | None
    ) -> None:
        await self.close()

    def resolve(self, name: str) -> str:
        """A name as this node sees it (its namespace; ``~x`` is private)."""
        return self.core.resolve(name)

    def _check_open(self) -> None:
        if not self.started or self.closed:
            raise UsageError(f"node {self.core.name} is not running", hint="start() it first")

    # topics ---------------------------------------------------------------------------

    async def advertise(
        self, topic: str, msg_type: str, *, latch: bool = False, queue_size: int = 100
    ) -> AsyncPublisher:
        """A publisher of ``msg_type`` on ``topic`` (rospy's ``Publisher``).

        One per topic: the first call decides its type, latching and queue.
        """
        self._check_open()
        core = await self.core.advertise(
            topic, messages.topic_type(msg_type), latch=latch, queue_size=queue_size
        )
        if core.type.type != msg_type:
            raise UsageError(f"{core.topic} is already advertised as {core.type.type}")
        return AsyncPublisher(core)

    async def publish(
        self, topic: str, msg: Values, msg_type: str | None = None, *, latch: bool = True
    ) -> AsyncPublisher:
        """Publish one message, advertising the topic first if need be.

        ``msg_type`` may be left out for a message object, or for a topic whose type the
        master knows. The topic latches by default, as ``rostopic pub`` does, so subscribers
        that connect later still get the message.
        """
        self._check_open()
        name = self.resolve(topic)
        existing = self.core.publishers.get(name)
        if msg_type is None:
            if isinstance(msg, Message):
                msg_type = msg._type
            elif existing is not None:
                msg_type = existing.type.type
            else:
                msg_type = await self._topic_type(name)
        pub = await self.advertise(name, msg_type, latch=latch)
        pub.publish(msg)
        return pub

    async def _topic_type(self, name: str) -> str:
        types = await self.core.master.topic_types()
        found = types.get(name)
        if not isinstance(found, str) or found == "*":
            raise UsageError(
                f"the type of {name} is not known", hint="give msg_type, or a message object"
            )
        return found

    async def subscribe(
        self,
        topic: str,
        callback: Callback | None = None,
        msg_type: str | None = None,
        *,
        queue_size: int = QUEUE_SIZE,
    ) -> AsyncSubscription:
        """Receive ``topic``: with ``callback``, or iterate the returned subscription.

        The type is learnt from the publishers; ``msg_type`` only keeps the messages of
        that type. ``AsyncNode`` calls ``callback`` on the loop, ``Node`` on the
        subscription's own thread, one message at a time.
        """
        self._check_open()
        shared = await self._topic(topic)
        sub = AsyncSubscription(shared, msg_type, callback, queue_size)
        shared.listeners.append(sub)
        return sub

    async def listen_raw(
        self, topic: str, callback: RawCallback
    ) -> Callable[[], Coroutine[Any, Any, None]]:
        """Bytes, header and arrival time of each message, undecoded; returns the undo."""
        self._check_open()
        shared = await self._topic(topic)
        shared.raw.append(callback)
        return lambda: shared.remove(callback)

    async def _topic(self, topic: str) -> _Topic:
        name = self.resolve(topic)
        shared = self._topics.get(name)
        if shared is None:
            shared = self._topics[name] = _Topic(self, name)
            try:
                await shared.start()
            except BaseException:
                del self._topics[name]
                raise
        return shared

    async def _unsubscribe(self, shared: _Topic) -> None:
        if self._topics.get(shared.name) is not shared:
            return
        del self._topics[shared.name]
        core = self.core.subscribers.pop(shared.name, None)
        if core is not None:
            await core.close()
        if not self.closed:
            try:
                await self.core.master.unregister_subscriber(shared.name, self.core.uri)
            except RostoolsError as err:
                log.debug("unregistering %s: %s", shared.name, err)

    async def wait_for_message(
        self, topic: str, timeout: float | None = None, msg_type: str | None = None
    ) -> Message:
        """The next message on ``topic`` (rospy's ``wait_for_message``)."""
        sub = await self.subscribe(topic, msg_type=msg_type, queue_size=1)
        try:
            return await sub.get(timeout)
        finally:
            await sub.close()

    def last_messages(self) -> dict[str, Message | bytes | None]:
        """The last message of every topic this node subscribes to (for reports)."""
        return {name: shared.last_message() for name, shared in sorted(self._topics.items())}

    # services -------------------------------------------------------------------------

    async def call_service(
        self,
        service: str,
        request: Values = None,
        srv_type: str | None = None,
        *,
        timeout: float = SERVICE_TIMEOUT,
        **fields: Any,
    ) -> Message:
        """Call ``service`` with a request (a message, dict, list, YAML or keywords).

        The type is asked of the server when not given.
        """
        self._check_open()
        name = self.resolve(service)
        client = self._clients.get(name)
        if client is None or (srv_type is not None and (client.type or ("",))[0] != srv_type):
            if srv_type is None:
                found = await ServiceClient(self.core, name).probe(timeout)
                srv_type = found.get("type", "")
                if not srv_type:
                    raise RostoolsError(f"service {name} did not say its type")
            req, _, md5 = messages.service_types(srv_type)
            # a connection per call, as rospy's ServiceProxy: a server restarted elsewhere
            # is found again by the next call
            client = self._clients[name] = ServiceClient(
                self.core, name, ServiceType(srv_type, md5)
            )
        assert client.type is not None
        req, resp, _ = messages.service_types(client.type.type)
        payload = messages.message(req, request, **fields).serialize()
        try:
            answer = await client.call(payload, timeout)
        except RostoolsError:
            client.close()
            self._clients.pop(name, None)
            raise
        return messages.decoder(resp, "", "")(answer)

    async def advertise_service(
        self,
        service: str,
        srv_type: str,
        handler: Callable[[Message], Values | Awaitable[Values]],
    ) -> ServiceServer:
        """Serve ``service``: ``handler(request)`` returns the response (message, dict, ...).

        A handler that raises answers the caller with a failure and the error's text.
        ``AsyncNode`` calls it on the loop (it may be a coroutine function), ``Node`` on a
        worker thread.
        """
        self._check_open()
        req, resp, md5 = messages.service_types(srv_type)
        decode = messages.decoder(req, "", "")

        async def serve(data: bytes) -> bytes:
            try:
                request = decode(data)
            except DecodeError as err:  # the client's bytes: one line, in words, to the client
                raise ServiceError(str(err)) from err
            result = handler(request)
            if inspect.isawaitable(result):
                result = await result
            return messages.message(resp, result).serialize()

        return await self.core.advertise_service(service, ServiceType(srv_type, md5), serve)

    async def wait_for_service(self, service: str, timeout: float | None = None) -> None:
        """Until the master knows ``service`` (rospy's ``wait_for_service``)."""
        self._check_open()
        name = self.resolve(service)
        deadline = None if timeout is None else time.monotonic() + timeout
        while True:
            try:
                await self.core.master.lookup_service(name)
                return
            except NotFoundError:
                pass
            if deadline is not None and time.monotonic() >= deadline:
                raise TimeoutExpired(f"service {name} did not appear within {timeout:g} s")
            await asyncio.sleep(0.05)

    # parameters -----------------------------------------------------------------------

    _MISSING: Any = object()

    async def get_param(self, key: str, default: Any = _MISSING) -> Any:
        """A parameter's value; ``default`` when unset, else ``NotFoundError``."""
        self._check_open()
        name = self.resolve(key)
        try:
            return await self.core.master.get_param(name)
        except NotFoundError:
            if default is not AsyncNode._MISSING:
                return default
            raise

    async def set_param(self, key: str, value: Any) -> None:
        """Set a parameter (a dict sets a tree)."""
        self._check_open()
        await self.core.master.set_param(self.resolve(key), value)

    async def has_param(self, key: str) -> bool:
        """Whether a parameter is set."""
        self._check_open()
        return await self.core.master.has_param(self.resolve(key))

    async def delete_param(self, key: str) -> None:
        """Delete a parameter; ``NotFoundError`` when unset."""
        self._check_open()
        await self.core.master.delete_param(self.resolve(key))
