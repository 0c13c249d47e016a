"""The bundled master, running: the Master/Parameter API served on asyncio.

``MasterServer`` runs on the caller's event loop; ``MasterThread`` runs one in a background thread,
which is how tests and ``rostools demo`` start and stop a master on a free port.
"""

from __future__ import annotations

import asyncio
import threading
from types import TracebackType
from typing import Any

from rostools.master.master_api import MasterAPI
from rostools.node.rpc import Encoded, Notifier, XmlRpcServer
from rostools.wire.xmlvalues import dumps_response

_READ_ONLY = frozenset(("getSystemState", "getTopicTypes", "getPublishedTopics", "getUri"))
#: Calls that change nothing the cache holds (nodes poll lookupNode to notice a restart).
_QUERIES = frozenset(
    ("lookupNode", "lookupService", "getPid", "getParam", "hasParam", "getParamNames")
)


class MasterServer:
    """A ROS master and parameter server on the running event loop."""

    def __init__(self, host: str = "127.0.0.1", port: int = 11311, advertise: str | None = None):
        self.host = host
        self.port = port
        self.advertise = advertise
        self.api: MasterAPI | None = None
        self.server: XmlRpcServer | None = None
        self.notifier: Notifier | None = None
        self.stopped = asyncio.Event()
        # Encoded answers to read-only calls: busy graphs poll getSystemState a lot, and
        # marshalling a big state is most of the cost of answering it.
        self._cache: dict[tuple[Any, ...], Encoded] = {}

    @property
    def uri(self) -> str:
        """``http://host:port/``, as nodes should reach it."""
        host = self.advertise or (
            "localhost" if self.host in ("127.0.0.1", "localhost") else self.host
        )
        return f"http://{host}:{self.port}/"

    async def start(self) -> None:
        """Bind the port and serve."""
        self.server = XmlRpcServer(self._dispatch, self.host, self.port, self._after_call)
        await self.server.start()
        self.port = self.server.port
        self.api = MasterAPI(self.uri)
        self.notifier = Notifier()

    def _dispatch(self, method: str, params: tuple[Any, ...]) -> Any:
        api = self.api
        assert api is not None
        if method not in _READ_ONLY:
            if method not in _QUERIES:
                self._cache.clear()  # anything else may change the state the cache holds
            return api.call(method, params)
        key = api.cache_key(method, params)
        if key is None:
            return api.call(method, params)  # a call that fails its checks: answered afresh
        cached = self._cache.get(key)
        if cached is None:
            result = api.call(method, params)
            if result[0] != 1:
                return result
            cached = self._cache[key] = Encoded(dumps_response(result))
        return cached

    def _after_call(self) -> None:
        api, notifier = self.api, self.notifier
        assert api is not None and notifier is not None
        for call in api.outgoing:
            notifier.send(call.uri, call.method, call.args)
        api.outgoing.clear()
        if api.shutdown_requested is not None:
            self.stopped.set()

    async def stop(self) -> None:
        """Stop serving and drop pending notifications."""
        if self.server is not None:
            await self.server.close()
        if self.notifier is not None:
            await self.notifier.close()
        self.stopped.set()

    async def wait(self) -> None:
        """Until a ``shutdown`` call or ``stop()``."""
        await self.stopped.wait()


class MasterThread:
    """A master in a background thread: ``with MasterThread() as m: ... m.uri``."""

    def __init__(self, host: str = "127.0.0.1", port: int = 0) -> None:
        self.host = host
        self.port = port
        self.master: MasterServer | None = None
        self.loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None
        self._ready = threading.Event()
        self._error: BaseException | None = None

    @property
    def uri(self) -> str:
        """The running master's URI."""
        assert self.master is not None
        return self.master.uri

    def start(self) -> MasterThread:
        """Start and wait until the port is bound."""
        self._thread = threading.Thread(target=self._run, name="rostools-master", daemon=True)
        self._thread.start()
        self._ready.wait()
        if self._error is not None:
            raise self._error
        return self

    def _run(self) -> None:
        async def main() -> None:
            self.loop = asyncio.get_running_loop()
            self.master = MasterServer(self.host, self.port)
            try:
                await self.master.start()
            except BaseException as err:  # noqa: BLE001 - handed to the starting thread
                self._error = err
                self._ready.set()
                return
            self._ready.set()
            await self.master.wait()
            await self.master.stop()

        asyncio.run(main())

    def stop(self) -> None:
        """Stop the master and join its thread."""
        if self.loop is not None and self.master is not None and self._thread is not None:
            if self._thread.is_alive():
                self.loop.call_soon_threadsafe(self.master.stopped.set)
            self._thread.join(timeout=10)

    def __enter__(self) -> MasterThread:
        return self.start()

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.stop()
