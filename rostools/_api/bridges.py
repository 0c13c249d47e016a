"""``bridge()``: the live graph over WebSocket (Foxglove protocol) from a script or a test.

``with rostools.bridge() as b:`` serves on a free loopback port on the API's loop; ``b.url``
is what a Foxglove client connects to. ``async with`` runs it on the caller's loop.
"""

from __future__ import annotations

import asyncio
from collections.abc import Mapping, Sequence

from rostools._api import exiting, loop, messages
from rostools._api.asyncnode import default_master_uri
from rostools.errors import RostoolsError, TimeoutExpired, UsageError
from rostools.node.node import LiveNode
from rostools.web.options import BridgeOptions
from rostools.web.server import Bridge

#: How long the bridge may take to listen and read the graph before it gives up.
START_TIMEOUT = 10.0


class WebBridge(loop.Lifecycle):
    """A running ``rostools bridge``, on a node of its own."""

    def __init__(self, opts: BridgeOptions, master_uri: str | None = None) -> None:
        self.opts = opts
        self.master_uri = master_uri
        self.server: Bridge | None = None
        self._node: LiveNode | None = None
        self._stop: asyncio.Event | None = None
        self._task: asyncio.Task[None] | None = None
        self._on_api_loop = False

    @property
    def url(self) -> str:
        """``ws://127.0.0.1:PORT``: where clients connect (add ``/?token=...`` if one is set)."""
        if self.server is None:
            raise UsageError("the bridge is not running", hint="start() it first")
        return self.server.url

    @property
    def port(self) -> int:
        """The port it listens on."""
        return self.server.port if self.server is not None else self.opts.port

    @property
    def clients(self) -> int:
        """How many clients are connected."""
        return len(self.server.clients) if self.server is not None else 0

    async def start_async(self) -> WebBridge:
        """Start serving on the running event loop; returns once clients can connect."""
        node = LiveNode("rostools_bridge", self.master_uri or default_master_uri(),
                        anonymous_name=True)  # fmt: skip
        await node.start()
        self._node, self._stop = node, asyncio.Event()
        exiting.track(node, self._finish)
        server = self.server = Bridge(node, self.opts, messages.store())
        ready: asyncio.Future[None] = asyncio.get_running_loop().create_future()

        def listening(_: Bridge) -> None:
            if not ready.done():
                ready.set_result(None)

        self._task = asyncio.get_running_loop().create_task(server.run(self._stop, listening))
        done, _ = await asyncio.wait([ready, self._task], timeout=START_TIMEOUT,
                                     return_when=asyncio.FIRST_COMPLETED)  # fmt: skip
        if ready not in done:
            error = self._task.exception() if self._task in done else None
            await self._finish()
            if isinstance(error, RostoolsError):
                raise error
            raise TimeoutExpired(f"the bridge did not start within {START_TIMEOUT:g} s",
                                 hint="is the master running?")  # fmt: skip
        return self

    async def _finish(self) -> None:
        if self._stop is not None:
            self._stop.set()
        try:
            if self._task is not None:
                await asyncio.gather(self._task, return_exceptions=True)
        finally:
            if self._node is not None:
                node, self._node = self._node, None
                try:
                    await node.close()
                finally:
                    exiting.forget(node)

    async def stop_async(self) -> None:
        """Stop serving, and close every client's connection."""
        await self._finish()

    def start(self) -> WebBridge:
        """Start on the API's background loop."""
        self._on_api_loop = True
        exiting.take_sigterm()
        return loop.run(self.start_async())

    def stop(self) -> None:
        """Stop serving."""
        if self._on_api_loop and self._node is not None:
            loop.run(self._finish())


def bridge(
    topics: Sequence[str] = (),
    *,
    master_uri: str | None = None,
    port: int = 0,
    address: str = "127.0.0.1",
    token: str = "",
    max_rates: Mapping[str, float] | None = None,
    read_only: bool = False,
    exclude: Sequence[str] = (),
) -> WebBridge:
    """A bridge of ``topics`` (none: all), not started: use it in a ``with``.

    ``port=0`` takes a free port. As ``rostools bridge``, it listens on loopback unless
    ``address`` says otherwise, and asks clients for ``token`` when one is given.
    """
    opts = BridgeOptions(
        topics=list(topics), exclude=list(exclude), address=address, port=port, token=token,
        max_rates=dict(max_rates or {}), read_only=read_only,
    )  # fmt: skip
    return WebBridge(opts, master_uri)
