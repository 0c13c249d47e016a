"""A rosbridge v2 client of the bridge: what it subscribed, advertised and serves.

``rosbridge.py`` acts on its topics and ``rbservices.py`` on its services; both keep their
state here, so neither imports the other's.
"""

from __future__ import annotations

import asyncio
import itertools
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from rostools.web.client import Client, Subscription
from rostools.wire import rosbridge as rb


class RosbridgeClient(Client):
    """A client that speaks rosbridge v2."""

    foxglove = False

    def __init__(self, socket: Any, name: str, on_gone: Callable[[Client], None]) -> None:
        super().__init__(socket, name, on_gone)
        self.level = rb.DEFAULT_LEVEL
        #: Set by any message that carries ``fragment_size``, as in rosbridge.
        self.fragment_size: int | None = None
        self.topics: dict[str, TopicSubs] = {}
        #: topic -> the ids of its advertisements (None for one without an id, or by publish)
        self.advertised: dict[str, set[Any]] = {}
        #: services this client serves (``advertise_service``)
        self.served: dict[str, Served] = {}
        self.fragments = rb.Fragments()
        self.fragment_ids = itertools.count()
        self.calls = 0

    def status(self, level: int, text: str) -> None:
        """A status of the bridge's own (a Foxglove level: 0 info, 1 warning, 2 error)."""
        self.tell(rb.LEVELS[min(max(level, 0), 2)], text)

    def tell(self, level: str, text: str, ident: Any = None) -> None:
        """A ``status`` message, if the client hears ``level``."""
        if rb.heard(level, self.level):
            self.send(rb.status(level, text, ident))

    def cut(self, text: str) -> Sequence[str]:
        """``text`` as it goes out: whole, or in fragments past the client's fragment size."""
        size = self.fragment_size
        if size is None or size <= 0 or len(text) <= size:
            return (text,)
        return rb.fragments(text, size, next(self.fragment_ids))


@dataclass
class TopicSubs:
    """A client's subscriptions to one topic, as one queue."""

    topic: str
    sub: Subscription
    #: subscription id (None for one without) -> what it asked: throttle_rate, queue_length,
    #: compression, type
    asks: dict[Any, dict[str, Any]] = field(default_factory=dict)

    @property
    def compression(self) -> str:
        """The strongest compression asked for."""
        asked = {a["compression"] for a in self.asks.values()}
        return max(asked, key=rb.COMPRESSIONS.index) if asked else "none"


@dataclass
class Served:
    """A service a client serves."""

    name: str
    client: RosbridgeClient
    request: str  # the request message's name
    response: str
    counter: itertools.count[int] = field(default_factory=lambda: itertools.count(1))
    pending: dict[str, asyncio.Future[Any]] = field(default_factory=dict)
