"""``bridge()``: the live graph over WebSocket (Foxglove protocol) from a script or a test.

``with rostools.bridge() as b:`` serves on a free loopback port on the API's loop; ``b.url``
is what a Foxglove client connects to. ``async with`` runs it on the caller's loop.
"""

from __future__ import annotations

import asyncio
from collections.abc import Mapping, Sequence

from rostools._api import messages
from rostools._api.nodetask import NodeTask
from rostools.errors import TimeoutExpired, UsageError
from rostools.web.options import BridgeOptions
from rostools.web.server import Bridge

#: How long the bridge may take to listen and read the graph before it gives up.
START_TIMEOUT = 10.0


class WebBridge(NodeTask):
    """A running ``rostools bridge``, on a node of its own."""

    node_name = "rostools_bridge"

    def __init__(self, opts: BridgeOptions, master_uri: str | None = None) -> None:
        super().__init__(master_uri)
        self.opts = opts
        self.server: Bridge | None = None

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
        node = await self._open_node()
        server = self.server = Bridge(node, self.opts, messages.store())
        ready: asyncio.Future[None] = asyncio.get_running_loop().create_future()

        def listening(_: Bridge) -> None:
            if not ready.done():
                ready.set_result(None)

        self._launch(node, lambda stop: server.run(stop, listening))
        assert self._task is not None
        done, _ = await asyncio.wait([ready, self._task], timeout=START_TIMEOUT,
                                     return_when=asyncio.FIRST_COMPLETED)  # fmt: skip
        if ready not in done:
            await self._finish()  # raises the bridge's own error, if it stopped with one
            raise TimeoutExpired(f"the bridge did not start within {START_TIMEOUT:g} s",
                                 hint="is the master running?")  # fmt: skip
        return self

    async def stop_async(self) -> None:
        """Stop serving, and close every client's connection."""
        await self._finish()

    def start(self) -> WebBridge:
        """Start on the API's background loop."""
        return self._start_on_api_loop()

    def stop(self) -> None:
        """Stop serving."""
        self._stop_on_api_loop()


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
    protocol: str = "both",
) -> WebBridge:
    """A bridge of ``topics`` (none: all), not started: use it in a ``with``.

    ``port=0`` takes a free port. As ``rostools bridge``, it listens on loopback unless
    ``address`` says otherwise, and asks clients for ``token`` when one is given. It speaks
    the Foxglove protocol to clients that offer its subprotocol and rosbridge v2 to the rest;
    ``protocol`` ("foxglove", "rosbridge") keeps it to one.
    """
    opts = BridgeOptions(
        topics=list(topics), exclude=list(exclude), address=address, port=port, token=token,
        max_rates=dict(max_rates or {}), read_only=read_only, protocol=protocol,
    )  # fmt: skip
    return WebBridge(opts, master_uri)
