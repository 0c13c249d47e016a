"""``Node``: the blocking node for scripts and tests, an ``AsyncNode`` on the API's loop.

Each method runs the ``AsyncNode`` method of the same name on the background loop
(``loop.run``) and waits for it; callbacks run on a thread of their own, so they may call
the blocking API themselves.
"""

from __future__ import annotations

import asyncio
import queue
import threading
from collections.abc import Callable, Iterator
from types import TracebackType
from typing import Any

from rostools._api import exiting, loop, messages
from rostools._api.asyncnode import AsyncNode, AsyncPublisher, AsyncSubscription, Callback, log
from rostools._api.messages import Values
from rostools.msgs.message import Message
from rostools.node.service import ServiceServer
from rostools.rosgraph.masterapi import SERVICE_TIMEOUT

_STOP = object()


class Publisher:
    """Publishes typed messages on one topic (from any thread)."""

    def __init__(self, inner: AsyncPublisher) -> None:
        self.inner = inner
        self.topic = inner.topic
        self.msg_type = inner.msg_type

    @property
    def subscriber_count(self) -> int:
        """How many subscribers are connected now."""
        return self.inner.subscriber_count

    def serialize(self, msg: Values) -> bytes:
        """The wire bytes of ``msg`` (a message, dict, list or YAML), checked against the type."""
        return messages.message(self.msg_type, msg).serialize()

    def publish(self, msg: Values = None, /, **fields: Any) -> None:
        """Send a message (a message object, dict, list, YAML text, or field keywords).

        The message is built and checked here, so a bad value raises in the caller.
        """
        data = messages.message(self.msg_type, msg, **fields).serialize()
        loop.loop().call_soon_threadsafe(self.inner.core.publish, data)

    def wait_for_subscribers(self, count: int = 1, timeout: float | None = None) -> None:
        """Until ``count`` subscribers are connected; ``TimeoutExpired`` after ``timeout``."""
        loop.run(self.inner.wait_for_subscribers(count, timeout))


class Subscription:
    """Messages of one topic: ``for msg in sub``, ``sub.get(timeout)``, or a callback.

    A callback runs on the subscription's own thread, one message at a time, in order.
    """

    def __init__(
        self,
        inner: AsyncSubscription,
        pending: queue.SimpleQueue[Any] | None = None,
        callback: Callback | None = None,
    ) -> None:
        """``pending``: where the loop queues messages for ``callback``, which a thread calls."""
        self.inner = inner
        self.topic = inner.topic
        self._thread: threading.Thread | None = None
        self._queue = pending
        if pending is not None and callback is not None:
            self._thread = threading.Thread(
                target=self._dispatch, args=(callback,), name=f"rostools {self.topic}",
                daemon=True,
            )  # fmt: skip
            self._thread.start()

    def _dispatch(self, callback: Callback) -> None:
        assert self._queue is not None
        while (msg := self._queue.get()) is not _STOP:
            try:
                callback(msg)
            except Exception:  # noqa: BLE001 - logged; the next message still comes
                log.exception("subscriber callback on %s failed", self.topic)

    @property
    def count(self) -> int:
        """Messages received so far."""
        return self.inner.count

    @property
    def last(self) -> Message | None:
        """The last message received."""
        return self.inner.last

    def get(self, timeout: float | None = None) -> Message:
        """The next message; ``TimeoutExpired`` after ``timeout`` seconds."""
        return loop.run(self.inner.get(timeout))

    def __iter__(self) -> Iterator[Message]:
        while not self.inner.closed or self.inner.queue:
            try:
                yield self.get()
            except Exception:
                if self.inner.closed:
                    return
                raise

    def close(self) -> None:
        """Stop receiving."""
        if not self.inner.closed:
            loop.run(self.inner.close())
        if self._thread is not None and self._queue is not None:
            self._queue.put(_STOP)
            if threading.current_thread() is not self._thread:
                self._thread.join(timeout=5)

    def __enter__(self) -> Subscription:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, err: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()


class Node:
    """A ROS node for scripts: ``with Node("name") as node: node.publish(...)``.

    It starts at once, on ``master_uri`` (default: ``ROS_MASTER_URI``); ``close()`` (or the
    end of the ``with``) unregisters it, and so does the end of the process, however it ends
    (``exiting.py``).
    """

    def __init__(
        self,
        name: str = "rostools_api",
        master_uri: str | None = None,
        *,
        anonymous: bool = True,
        namespace: str | None = None,
    ) -> None:
        self.aio = AsyncNode(name, master_uri, anonymous=anonymous, namespace=namespace)
        exiting.take_sigterm()  # here, on the caller's thread: the start runs on the loop's
        loop.run(self.aio.start())

    @property
    def name(self) -> str:
        """The node's full name."""
        return self.aio.name

    @property
    def master_uri(self) -> str:
        """The master this node registers with."""
        return self.aio.master_uri

    @property
    def uri(self) -> str:
        """The node's slave API URI."""
        return self.aio.uri

    @property
    def closed(self) -> bool:
        """Whether ``close()`` was called."""
        return self.aio.closed

    def close(self) -> None:
        """Unregister everything and close every connection; only the first close does it."""
        if not self.aio.closed:
            loop.run(self.aio.close())

    def __enter__(self) -> Node:
        return self

    def __exit__(
        self, kind: type[BaseException] | None, err: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.close()

    def resolve(self, name: str) -> str:
        """A name as this node sees it (its namespace; ``~x`` is private)."""
        return self.aio.resolve(name)

    def advertise(
        self, topic: str, msg_type: str, *, latch: bool = False, queue_size: int = 100
    ) -> Publisher:
        """A publisher of ``msg_type`` on ``topic`` (rospy's ``Publisher``).

        One per topic: the first call decides its type, latching and queue.
        """
        return Publisher(
            loop.run(self.aio.advertise(topic, msg_type, latch=latch, queue_size=queue_size))
        )

    def publish(
        self, topic: str, msg: Values, msg_type: str | None = None, *, latch: bool = True
    ) -> Publisher:
        """Publish one message, advertising the topic first if need be.

        ``msg_type`` may be left out for a message object, or for a topic whose type the
        master knows. The topic latches by default, as ``rostopic pub`` does, so subscribers
        that connect later still get the message.
        """
        return Publisher(loop.run(self.aio.publish(topic, msg, msg_type, latch=latch)))

    def subscribe(
        self,
        topic: str,
        callback: Callback | None = None,
        msg_type: str | None = None,
        *,
        queue_size: int = 1000,
    ) -> Subscription:
        """Receive ``topic``: with ``callback``, or iterate the returned subscription.

        The type is learnt from the publishers; ``msg_type`` only keeps the messages of
        that type. ``AsyncNode`` calls ``callback`` on the loop, ``Node`` on the
        subscription's own thread, one message at a time.
        """
        if callback is None:
            return Subscription(
                loop.run(self.aio.subscribe(topic, None, msg_type, queue_size=queue_size))
            )
        # Messages are queued from the first one on; the thread that calls back starts after.
        pending: queue.SimpleQueue[Any] = queue.SimpleQueue()
        inner = loop.run(self.aio.subscribe(topic, pending.put, msg_type, queue_size=queue_size))
        return Subscription(inner, pending, callback)

    def wait_for_message(
        self, topic: str, timeout: float | None = None, msg_type: str | None = None
    ) -> Message:
        """The next message on ``topic`` (rospy's ``wait_for_message``)."""
        return loop.run(self.aio.wait_for_message(topic, timeout, msg_type))

    def last_messages(self) -> dict[str, Message | bytes | None]:
        """The last message of every topic this node subscribes to (for reports)."""
        return loop.run(_call(self.aio.last_messages))

    def call_service(
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
        return loop.run(
            self.aio.call_service(service, request, srv_type, timeout=timeout, **fields)
        )

    def advertise_service(
        self, service: str, srv_type: str, handler: Callable[[Message], Values]
    ) -> ServiceServer:
        """Serve ``service``: ``handler(request)`` returns the response (message, dict, ...).

        A handler that raises answers the caller with a failure and the error's text.
        ``AsyncNode`` calls it on the loop (it may be a coroutine function), ``Node`` on a
        worker thread.
        """

        async def in_thread(request: Message) -> Values:
            return await asyncio.get_running_loop().run_in_executor(None, handler, request)

        return loop.run(self.aio.advertise_service(service, srv_type, in_thread))

    def wait_for_service(self, service: str, timeout: float | None = None) -> None:
        """Until the master knows ``service`` (rospy's ``wait_for_service``)."""
        loop.run(self.aio.wait_for_service(service, timeout))

    def get_param(self, key: str, default: Any = AsyncNode._MISSING) -> Any:
        """A parameter's value; ``default`` when unset, else ``NotFoundError``."""
        return loop.run(self.aio.get_param(key, default))

    def set_param(self, key: str, value: Any) -> None:
        """Set a parameter (a dict sets a tree)."""
        loop.run(self.aio.set_param(key, value))

    def has_param(self, key: str) -> bool:
        """Whether a parameter is set."""
        return loop.run(self.aio.has_param(key))

    def delete_param(self, key: str) -> None:
        """Delete a parameter; ``NotFoundError`` when unset."""
        loop.run(self.aio.delete_param(key))


async def _call(fn: Callable[[], Any]) -> Any:
    """``fn()`` on the loop (what it reads is the loop's to change)."""
    return fn()
