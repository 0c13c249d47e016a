"""``Master``: the bundled master, started in-process on a free port and stopped.

``with Master() as m`` runs it on the API's background loop; ``async with Master() as m``
on the caller's own loop. Either way ``m.uri`` is what nodes are given.
"""

from __future__ import annotations

from rostools._api import loop
from rostools.errors import UsageError
from rostools.master.core import start_master
from rostools.master.server import MasterServer


class Master(loop.Lifecycle):
    """A ROS master and parameter server in this process.

    ``port=0`` (the default) takes a free port; ``host`` is where it listens and the
    address its URI gives out. The parameters roscore sets (``/run_id``,
    ``/rosdistro``, ``/rosversion``) are set; no ``/rosout`` node is started.
    """

    def __init__(self, port: int = 0, host: str = "127.0.0.1") -> None:
        self.host = host
        self._port = port
        self.core: MasterServer | None = None
        self._on_api_loop = False

    @property
    def uri(self) -> str:
        """``http://host:port/``, as nodes reach it."""
        if self.core is None:
            raise UsageError("the master is not running", hint="start() it first")
        return self.core.uri

    @property
    def port(self) -> int:
        """The port it listens on."""
        return self.core.port if self.core is not None else self._port

    @property
    def running(self) -> bool:
        """Whether it serves."""
        return self.core is not None and not self.core.stopped.is_set()

    async def start_async(self) -> Master:
        """Start serving on the running event loop."""
        core = await start_master(
            self.host, self._port, self.host,
            "another program holds the port; pick another, or 0 for a free one",
        )  # fmt: skip
        self.core = core
        return self

    async def stop_async(self) -> None:
        """Stop serving (on the loop it runs on)."""
        if self.core is not None:
            await self.core.stop()

    def start(self) -> Master:
        """Start serving on the API's background loop."""
        self._on_api_loop = True
        return loop.run(self.start_async())

    def stop(self) -> None:
        """Stop serving."""
        if self.core is not None and self._on_api_loop:
            loop.run(self.stop_async())
