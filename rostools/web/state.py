"""What the bridge's parts share: its node, options, channels, services, clients and events.

``server.Bridge`` builds on it, and ``operations.Operations`` (what clients ask) works on it,
so neither imports the other.
"""

from __future__ import annotations

import asyncio
import itertools
import logging
import time
from collections.abc import Callable, Coroutine
from typing import Any

from rostools.msgs.store import TypeStore
from rostools.node.clock import RosClock
from rostools.node.node import LiveNode
from rostools.web.channels import Channel, Links
from rostools.web.client import Client
from rostools.web.graph import Graph, GraphWatch
from rostools.web.options import BridgeOptions
from rostools.web.services import Service, Services

log = logging.getLogger(__name__)

Event = dict[str, Any]


class BridgeState:
    """The bridge's state, and the few acts every part of it needs."""

    links: Links
    graph: GraphWatch

    def __init__(
        self,
        node: LiveNode,
        opts: BridgeOptions,
        store: TypeStore,
        on_event: Callable[[Event], None] | None = None,
    ) -> None:
        self.node = node
        self.opts = opts
        self.store = store
        self.on_event = on_event or (lambda _: None)
        self.ids = itertools.count(1)
        self.channels: dict[int, Channel] = {}
        self.by_topic: dict[str, Channel] = {}
        self.services: dict[int, Service] = {}
        self.service_ids: dict[str, int] = {}
        self.clients: set[Client] = set()
        self.clock = RosClock()
        self.describer = Services(node, store)
        self.port = 0
        self.started = time.monotonic()
        self._tasks: set[asyncio.Task[Any]] = set()

    @property
    def url(self) -> str:
        """The URL a client connects to (the token left out)."""
        scheme = "wss" if self.opts.certfile else "ws"
        host = self.opts.address
        host = "127.0.0.1" if host in ("0.0.0.0", "") else host  # noqa: S104 - shown, not bound
        return f"{scheme}://{f'[{host}]' if ':' in host else host}:{self.port}"

    def event(self, kind: str, **fields: Any) -> None:
        """Tell the terminal (the live table, or a JSON line)."""
        self.on_event({"event": kind, **fields})

    def spawn(self, coro: Coroutine[Any, Any, Any]) -> None:
        """Run ``coro`` beside the loop, kept until done; an error is logged, not raised."""
        task = asyncio.get_running_loop().create_task(coro)
        self._tasks.add(task)
        task.add_done_callback(self._task_done)

    def _task_done(self, task: asyncio.Task[Any]) -> None:
        self._tasks.discard(task)
        if not task.cancelled() and task.exception() is not None:
            log.warning("bridge: %s", task.exception())

    def broadcast(self, message: dict[str, Any] | bytes) -> None:
        """Send one message to every Foxglove client."""
        for client in self.clients:
            if client.foxglove:
                client.send(message)

    def current_graph(self) -> Graph:
        """The graph at the last look."""
        return self.graph.graph
