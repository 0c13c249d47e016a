"""A node's watch on the master: register again after a restart, and name silent subscribers.

Neither rospy nor roscpp does either. After a roscore respawn their nodes stay invisible to
everyone who starts later. A subscriber that cannot reach its publisher is never reported on
the publisher's side. Ours notice both within a second or two and say so in one line.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Mapping
from typing import TYPE_CHECKING, Any, Protocol

from rostools.errors import NotFoundError
from rostools.node.notice import Notice
from rostools.rosgraph.masterapi import MasterError
from rostools.rosgraph.network import explain, uri_host

if TYPE_CHECKING:
    from rostools.node.endpoint import Owner
    from rostools.node.publisher import TopicPublisher
    from rostools.node.registration import Registrar
    from rostools.node.service import ServiceServer
    from rostools.node.subscriber import Subscriber

    class Registrations(Owner, Protocol):
        """A node as its watch sees it: what it has registered with the master."""

        @property
        def publishers(self) -> Mapping[str, TopicPublisher]:
            """Topic -> its publisher."""

        @property
        def subscribers(self) -> Mapping[str, Subscriber]:
            """Topic -> its subscriber."""

        @property
        def services(self) -> Mapping[str, ServiceServer]:
            """Service -> its server."""

        @property
        def registrar(self) -> Registrar:
            """Its registrations, and those being tried again."""


log = logging.getLogger(__name__)

#: How often a node with registrations checks that the master still knows it (s): a
#: restarted master has forgotten everything, and we register again within this and a call.
WATCH_PERIOD = 0.5
#: How long that check may take before the master counts as gone (s).
WATCH_TIMEOUT = 1.0
#: How long a subscriber registered for one of our topics may stay silent before we say so.
SILENT_AFTER = 3.0
#: How often we compare the master's subscribers with those that reached us (s).
SUBSCRIBER_CHECK_PERIOD = 1.0


class MasterWatch:
    """Runs beside a node from ``start`` until ``stop`` (the node's close)."""

    def __init__(self, node: Registrations) -> None:
        self.node = node
        self.stopped = False
        self._task: asyncio.Task[None] | None = None
        self.next_check = time.monotonic() + SUBSCRIBER_CHECK_PERIOD
        #: (topic, subscriber) -> when we first saw it registered and silent
        self.silent: dict[tuple[str, str], float] = {}
        self.told: set[tuple[str, str]] = set()

    def start(self) -> None:
        """Watch in a task of the running loop."""
        self._task = asyncio.get_running_loop().create_task(self.run())

    def stop(self) -> None:
        """Stop for good, before the node unregisters.

        The flag, not only the cancellation: Python 3.11's ``wait_for`` drops a cancellation
        that meets a finished call, and a watch going on would register the node again.
        """
        self.stopped = True
        if self._task is not None:
            self._task.cancel()

    async def run(self) -> None:
        """Check every ``WATCH_PERIOD`` while the node has anything registered."""
        node = self.node
        while not self.stopped:
            await asyncio.sleep(WATCH_PERIOD)
            if self.stopped or not (node.publishers or node.subscribers or node.services):
                continue
            try:
                await self._check_master()
                if node.publishers and time.monotonic() >= self.next_check:
                    self.next_check = time.monotonic() + SUBSCRIBER_CHECK_PERIOD
                    await self._check_subscribers()
            except Exception as err:  # noqa: BLE001 - any failure: the master is gone for now
                self._master_lost(err)

    async def _check_master(self) -> None:
        node = self.node
        # -1 means this master never heard of us. Another URI under our name means we were
        # replaced; then the master shuts us down itself.
        try:
            await node.master.lookup_node(node.name, timeout=WATCH_TIMEOUT)
            known = True
        except (NotFoundError, MasterError):  # -1: unknown here; another code: as unknown
            known = False
        if self.stopped:
            return
        # unknown before the master took anything of ours: the registrar is still trying
        if not known and node.registrar.confirmed:
            await self.register_again()
        elif node.master_lost:
            node.notify(Notice("master_back", f"the master at {node.master_uri} is back"))
        node.master_lost = False

    def _master_lost(self, err: BaseException) -> None:
        if self.node.master_lost:
            return
        self.node.master_lost = True
        uri = self.node.master_uri
        # our errors are raised from the transport's, which says why
        reason = explain(err.__cause__ or err, uri_host(uri), peer=False).reason
        self.node.notify(
            Notice(
                "master_lost",
                f"the master at {uri} does not answer ({reason}); carrying on, and "
                "registering again when it is back",
                {"uri": uri, "reason": reason},
            )
        )

    async def register_again(self) -> None:
        """Every publisher, subscriber and service, registered with a new master."""
        node = self.node
        subs = list(node.subscribers.values())
        calls: list[tuple[str, tuple[Any, ...]]] = [
            ("registerPublisher", (t, p.type.type, node.uri)) for t, p in node.publishers.items()
        ]
        calls += [("registerSubscriber", (s.topic, s.type.type, node.uri)) for s in subs]
        calls += [("registerService", (n, v.uri, node.uri)) for n, v in node.services.items()]
        for sub in subs:
            sub.master_restarted()
        results = await node.master.multicall(calls, WATCH_TIMEOUT * 5)
        for name in list(node.registrar.pending):  # registered now, with everything else
            node.registrar.forget(name)
        first_sub = len(node.publishers)
        for sub, result in zip(subs, results[first_sub : first_sub + len(subs)], strict=True):
            if isinstance(result, list):
                sub.update([u for u in result if isinstance(u, str)])
        node.notify(
            Notice(
                "master_restarted",
                f"the master at {node.master_uri} restarted; registered again "
                f"({len(node.publishers)} publications, {len(subs)} subscriptions, "
                f"{len(node.services)} services)",
                {"uri": node.master_uri},
            )
        )

    async def _check_subscribers(self) -> None:
        """Say once of each subscriber the master lists for our topics that never reached us."""
        node = self.node
        state = await node.master.system_state(WATCH_TIMEOUT)
        now = time.monotonic()
        listed: set[tuple[str, str]] = set()
        for topic, names in state[1]:
            pub = node.publishers.get(topic)
            if pub is None:
                continue
            for name in names:
                key = (topic, name)
                if name == node.name or name in pub.contacted or key in self.told:
                    continue
                listed.add(key)
                if now - self.silent.setdefault(key, now) >= SILENT_AFTER:
                    self.told.add(key)
                    self._tell_silent(topic, name)
        self.silent = {k: v for k, v in self.silent.items() if k in listed}

    def _tell_silent(self, topic: str, name: str) -> None:
        node = self.node
        self.node.notify(
            Notice(
                "subscriber_silent",
                f"{name} subscribes to {topic} but has not contacted us in {SILENT_AFTER:g} s: "
                f"it may not reach {node.uri} (set ROS_IP or ROS_HOSTNAME here to an address it "
                "reaches), or it died without unregistering",
                {"topic": topic, "node": name, "uri": node.uri},
            )
        )
