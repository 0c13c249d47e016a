"""A topic subscriber: connects to every publisher, follows publisherUpdate, reconnects.

A publisher it cannot reach is reported once (``Node.notify``), with the reason and a hint.

Frames are handed to the callback in batches, as they came off the socket, with the arrival
time: per-message work is the consumer's, in its own loop (hz at 200 kHz depends on it).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
import weakref
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from rostools.msgs.topictype import TopicType
from rostools.node.connection import Frame, InboundConnection
from rostools.node.mastercalls import peer_value
from rostools.node.notice import Notice
from rostools.node.rpc import CALL_TIMEOUT
from rostools.rosgraph.masterapi import MasterError
from rostools.rosgraph.network import Failure, explain, uri_host
from rostools.wire.tcpros import HANDSHAKE_TIMEOUT, MAX_FRAME, subscriber_header

if TYPE_CHECKING:
    from rostools.node.endpoint import Owner

log = logging.getLogger(__name__)

FramesCallback = Callable[[list[Frame], InboundConnection, float], None]
#: Waits between attempts to reach a publisher that is registered but not answering.
RETRY_FIRST, RETRY_MAX = 0.2, 5.0
#: A failure that may be a publisher on its way out is reported once it lasts this long (s).
REPORT_AFTER = 1.0
#: After a publisher closed a working connection, failures to connect again are reported
#: once they last this long (s): a node on its way out unregisters, closes, and refuses its
#: topics until the master's ``publisherUpdate`` tells us, which for a node of a thousand
#: topics on a busy machine takes seconds (a line for each topic was printed meanwhile).
REPORT_AFTER_DROP = 5.0
#: How long a TCP connect to a publisher may take: the OS's own wait is minutes.
CONNECT_TIMEOUT = 5.0
#: A publisher that timed out may take twice as long the next time, up to this many times the
#: usual limits (``CALL_TIMEOUT``, ``CONNECT_TIMEOUT``, ``HANDSHAKE_TIMEOUT``): a busy roscpp
#: node under load took longer than them all, and each try from scratch cost it more work.
MAX_SLOWNESS = 8.0
#: ``requestTopic`` calls in flight to one publisher at once. A recorder of a thousand topics
#: of one node asked them all at once; a busy roscpp node, answering one at a time, let most
#: time out, was asked again, and in the end answered hardly any in time.
PEER_CALLS = 4
#: The gate of each publisher's slave API, per event loop (gone once nobody waits at it).
_gates: weakref.WeakValueDictionary[tuple[asyncio.AbstractEventLoop, str], asyncio.Semaphore] = (
    weakref.WeakValueDictionary()
)


def _gate(uri: str) -> asyncio.Semaphore:
    """The gate that keeps ``PEER_CALLS`` calls at most in flight to the node at ``uri``."""
    key = (asyncio.get_running_loop(), uri)
    gate = _gates.get(key)
    if gate is None:
        gate = _gates[key] = asyncio.Semaphore(PEER_CALLS)
    return gate


class Subscriber:
    """Subscribes to one topic; ``type`` is learnt from the first publisher when it is ``*``."""

    def __init__(
        self,
        node: Owner,
        topic: str,
        topic_type: TopicType,
        callback: FramesCallback,
        tcp_nodelay: bool = False,
        max_frame: int = MAX_FRAME,
    ) -> None:
        self.node = node
        self.topic = topic
        self.type = topic_type
        self.callback = callback
        self.tcp_nodelay = tcp_nodelay
        self.max_frame = max_frame
        #: Seconds to let small reads gather before the next wake-up (0: read at once); for
        #: consumers that only count, where one wake-up per message would cost the CPU.
        self.coalesce = 0.0
        #: The callback is done with each frame when it returns: big frames share one buffer.
        self.reuse_frames = False
        self.publishers: set[str] = set()
        self.connections: dict[str, InboundConnection] = {}
        self.tasks: dict[str, asyncio.Task[None]] = {}
        self.closed = False
        self.on_header: Callable[[InboundConnection], None] | None = None
        #: Publishers whose live links predate a master restart (see ``master_restarted``).
        self.orphans: set[str] = set()
        #: The name each publisher gave in its header, by URI: who to name when it goes away.
        self.names: dict[str, str] = {}
        #: How many times longer than usual a publisher that was slow may take (1, 2, 4, ...).
        self.slowness: dict[str, float] = {}

    def update(self, uris: list[str]) -> None:
        """The publishers now (from registerSubscriber or publisherUpdate)."""
        self.orphans -= set(uris)
        # roscpp drops publishers no longer listed; those the master never listed stay
        keep = set(uris) | (self.orphans & set(self.connections))
        self.publishers = keep
        for uri in uris:
            if uri not in self.tasks and not self.closed:
                task = asyncio.get_running_loop().create_task(self._follow(uri))
                self.tasks[uri] = task
                task.add_done_callback(self._forget_task)
        for uri in list(self.connections):
            if uri not in keep:
                self.connections[uri].close()

    def master_restarted(self) -> None:
        """A new master knows none of our publishers: keep the live links it does not list.

        rospy and roscpp publishers never register again, so the new master will not list
        them; their connections stay until they close.
        """
        self.orphans = set(self.connections)

    def _forget_task(self, task: asyncio.Task[None]) -> None:
        for uri, known in list(self.tasks.items()):
            if known is task:
                del self.tasks[uri]

    async def _follow(self, uri: str) -> None:
        """Stay connected to ``uri`` while it is listed as a publisher.

        A publisher that cannot be reached is reported once, with the reason; we keep trying.
        """
        delay = RETRY_FIRST
        failing_since: float | None = None
        reported = False
        closed_by_peer = False  # it closed a working connection: it may be on its way out
        while not self.closed and uri in self.publishers:
            result = await self._connect(uri)
            if isinstance(result, InboundConnection):
                delay = RETRY_FIRST
                await result.closed
                self.connections.pop(uri, None)
                if uri in self.orphans:  # no master lists it: nothing to reconnect to
                    self.orphans.discard(uri)
                    self.publishers.discard(uri)
                    return
                failure = result.failure
                if result.timed_out:
                    self._slow(uri)
                if result.header is not None:  # it worked: was it closed by the peer?
                    closed_by_peer = failure is None
                if failure is None:
                    failing_since, reported = None, False
            else:
                failure = result
            if self.closed or uri not in self.publishers:
                return
            if failure is not None:
                now = time.monotonic()
                failing_since = failing_since or now
                if closed_by_peer:
                    due = now - failing_since >= REPORT_AFTER_DROP
                else:
                    due = failure.lasting or now - failing_since >= REPORT_AFTER
                if due and not reported and not self.node.master_lost:  # lists go stale then
                    reported = True
                    await self._report(uri, failure)
            await asyncio.sleep(delay)
            delay = min(delay * 2, RETRY_MAX)

    async def _report(self, uri: str, failure: Failure) -> None:
        name = self.names.get(uri) or await node_at(self.node, uri)
        who = f"{name} at {uri}" if name else uri
        hint = f"; {failure.hint}" if failure.hint else ""
        what = "dropped the connection from" if failure.dropped else "cannot connect to"
        self.node.notify(
            Notice(
                "peer_dropped" if failure.dropped else "peer_unreachable",
                f"{what} {who} (publisher of {self.topic}): {failure.reason}{hint}",
                {
                    "topic": self.topic,
                    "node": name,
                    "uri": uri,
                    "reason": failure.reason,
                    "hint": failure.hint,
                },
            )
        )

    async def _connect(self, uri: str) -> InboundConnection | Failure:
        """Ask ``uri`` for the topic and connect, ``PEER_CALLS`` at a time per publisher.

        The steps may take ``CALL_TIMEOUT``, ``CONNECT_TIMEOUT`` and then (the header,
        after the gate) ``HANDSHAKE_TIMEOUT``, twice as long after each time out (a busy
        publisher); the wait at the gate has no limit.
        """
        async with _gate(uri):
            result = await self._ask(uri)
            if isinstance(result, Failure):
                return result
            return await self._open(uri, *result)

    def _limit(self, uri: str, usual: float) -> float:
        """How long a step with ``uri`` may take: ``usual``, or longer if it was slow."""
        return usual * self.slowness.get(uri, 1.0)

    def _slow(self, uri: str, err: BaseException | None = None) -> None:
        """A step with ``uri`` timed out (as ``err``, if given, says): the next may take longer."""
        if err is None or isinstance(err, TimeoutError | asyncio.TimeoutError):
            self.slowness[uri] = min(self.slowness.get(uri, 1.0) * 2, MAX_SLOWNESS)

    async def _ask(self, uri: str) -> tuple[str, int] | Failure:
        """``requestTopic``: the publisher's TCPROS host and port, or why not."""
        limit = self._limit(uri, CALL_TIMEOUT)
        try:
            proto = await peer_value(
                uri, self.node.name, "requestTopic", self.topic, [["TCPROS"]], timeout=limit
            )
        except MasterError as err:
            refused = str(err)
        except Exception as err:  # noqa: BLE001 - any failure means: report, try again later
            log.debug("requestTopic %s at %s failed: %s", self.topic, uri, err)
            self._slow(uri, err)
            return explain(err, uri_host(uri))
        else:
            ok = isinstance(proto, list) and len(proto) >= 3 and proto[0] == "TCPROS"
            refused = "" if ok else f"no TCPROS in {proto!r}"
        if refused:
            log.debug("requestTopic %s at %s: %s", self.topic, uri, refused)
            # a node on its way out refuses the topics it already dropped (roscpp does, for
            # each of its topics): said only if it lasts
            return Failure(f"it refused the topic: {refused}", lasting=False)
        if type(proto[2]) is not int or not 0 < proto[2] < 65536:
            return Failure(f"it gave no port to connect to: {proto!r}")
        return str(proto[1]), proto[2]

    async def _open(self, uri: str, host: str, port: int) -> InboundConnection | Failure:
        """The TCPROS connection to the publisher at ``uri``, or why not."""
        header = subscriber_header(
            self.node.name, self.topic, self.type.md5sum, self.type.type, self.type.definition,
            self.tcp_nodelay,
        )  # fmt: skip
        loop = asyncio.get_running_loop()
        try:
            _, conn = await asyncio.wait_for(
                loop.create_connection(
                    lambda: InboundConnection(
                        self,
                        uri,
                        self.node.next_connection_id(),
                        header,
                        self._limit(uri, HANDSHAKE_TIMEOUT),
                    ),
                    host,
                    port,
                ),
                self._limit(uri, CONNECT_TIMEOUT),
            )
        except (OSError, asyncio.TimeoutError) as err:
            log.debug("connecting to %s:%s for %s failed: %s", host, port, self.topic, err)
            self._slow(uri, err)
            failure = explain(err, host)
            return Failure(f"its TCPROS port {host}:{port}: {failure.reason}", failure.hint,
                           failure.lasting)  # fmt: skip
        if self.closed:
            conn.close()
            return Failure("closed")
        self.connections[uri] = conn
        return conn

    def header_received(self, conn: InboundConnection) -> None:
        """A publisher answered: learn the type if we asked for ``*``."""
        if self.type.md5sum == "*" and conn.header is not None:
            self.type = TopicType.from_header(conn.header)
        self.slowness.pop(conn.publisher_uri, None)  # it answered in time
        caller = (conn.header or {}).get("callerid")
        if caller:
            self.names[conn.publisher_uri] = caller
        if self.on_header is not None:
            self.on_header(conn)

    def frames_received(self, frames: list[Frame], conn: InboundConnection, now: float) -> None:
        """Messages arrived."""
        if not self.closed:
            self.callback(frames, conn, now)

    def connection_closed(self, conn: InboundConnection) -> None:
        """A connection went away (the follow task reconnects if it should)."""
        if self.connections.get(conn.publisher_uri) is conn:
            del self.connections[conn.publisher_uri]

    def stats(self) -> list[Any]:
        """rospy's getBusStats entries for this subscription."""
        return [
            [c.id, c.bytes_received, c.messages_received, -1, True]
            for c in self.connections.values()
        ]

    async def close(self) -> None:
        """Disconnect from every publisher."""
        self.closed = True
        for conn in list(self.connections.values()):
            conn.close()
        for task in list(self.tasks.values()):
            task.cancel()
        for task in list(self.tasks.values()):
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await task


#: Seconds the publishers' names, once looked up, answer for their URIs. When a node with
#: many topics goes away unannounced, every topic reports it within a few seconds, and one
#: lookup names it for all (1,000 lookups at once, each reply ~100 KB parsed, took a
#: recorder from 40 MB to 280 MB; 200 dead publishers of /rosout cost the master 20,000 calls).
NAME_KEEP = 10.0
#: Publishers' names by slave API URI, by master: (when looked up, {uri: name}).
_names: dict[str, tuple[float, dict[str, str]]] = {}
#: Lookups under way, by event loop and master.
_lookups: dict[tuple[asyncio.AbstractEventLoop, str], asyncio.Future[dict[str, str]]] = {}


async def node_at(node: Owner, uri: str) -> str | None:
    """The name of the publisher whose slave API is ``uri``, if the master says.

    Every report within ``NAME_KEEP`` seconds shares one lookup of every publisher's name.
    """
    known = _names.get(node.master_uri)
    if known is None or time.monotonic() - known[0] >= NAME_KEEP:
        key = (asyncio.get_running_loop(), node.master_uri)
        lookup = _lookups.get(key)
        if lookup is None:
            lookup = _lookups[key] = asyncio.ensure_future(_keep_names(node))
            lookup.add_done_callback(lambda _: _lookups.pop(key, None))
        return (await asyncio.shield(lookup)).get(uri)
    return known[1].get(uri)


async def _keep_names(node: Owner) -> dict[str, str]:
    """``publisher_names``, kept before the lookup ends.

    Kept by those who waited for it, the names were missing between the lookup's end and
    their turn, and a report that came in between looked them all up again.
    """
    names = await publisher_names(node)
    _names[node.master_uri] = (time.monotonic(), names)
    return names


async def publisher_names(node: Owner) -> dict[str, str]:
    """The slave API URI of every publisher the master lists, and its name.

    Two calls whatever the number of publishers: the state, then every ``lookupNode`` in one
    multicall.
    """
    try:
        pubs, _, _ = await node.master.system_state()
        names = sorted({str(n) for _, nodes in pubs for n in nodes})
        answers = await node.master.multicall([("lookupNode", (n,)) for n in names])
    except Exception as err:  # noqa: BLE001 - the names only decorate messages
        log.debug("finding the publishers' names: %s", err)
        return {}
    return {uri: name for name, uri in zip(names, answers, strict=False) if isinstance(uri, str)}
