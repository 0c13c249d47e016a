"""One event loop on a daemon thread: where the blocking API runs the async one.

Every blocking call of the API is a coroutine of the async API run here, so there is one
implementation. The loop starts at the first call and lives as long as the process; its
blocking work runs on ``workers.Workers``, which serve until the process ends, so the nodes
can still reach their master as it exits (``exiting.py``).
"""

from __future__ import annotations

import asyncio
import concurrent.futures
import threading
from collections.abc import Coroutine
from types import TracebackType
from typing import Any, TypeVar

from rostools._api.workers import Workers
from rostools.errors import TimeoutExpired, UsageError

T = TypeVar("T")

_lock = threading.Lock()
_loop: asyncio.AbstractEventLoop | None = None
_thread: threading.Thread | None = None


def loop() -> asyncio.AbstractEventLoop:
    """The API's event loop, started on first use."""
    global _loop, _thread
    with _lock:
        if _loop is None:
            ready = threading.Event()
            made: list[asyncio.AbstractEventLoop] = []

            def serve() -> None:
                new = asyncio.new_event_loop()
                new.set_default_executor(Workers())
                made.append(new)
                ready.set()
                new.run_forever()

            _thread = threading.Thread(target=serve, name="rostools-api", daemon=True)
            _thread.start()
            ready.wait()
            _loop = made[0]
        return _loop


def on_loop_thread() -> bool:
    """Whether the caller runs on the API's loop (a callback of the async API)."""
    return _thread is not None and threading.current_thread() is _thread


def run(coro: Coroutine[Any, Any, T], timeout: float | None = None) -> T:
    """Run ``coro`` on the API's loop and wait for its result (its exception is raised here).

    ``timeout`` bounds the wait: the coroutine is cancelled and ``TimeoutExpired`` raised.
    """
    if on_loop_thread():
        coro.close()
        raise UsageError(
            "a blocking rostools call from the API's own event loop would wait forever",
            hint="in async code use AsyncNode and await its methods",
        )
    future = asyncio.run_coroutine_threadsafe(coro, loop())
    try:
        return future.result(timeout)
    except concurrent.futures.TimeoutError:
        future.cancel()
        raise TimeoutExpired(f"no result within {timeout:g} s") from None
    except BaseException:
        future.cancel()  # Ctrl-C in the caller: the work on the loop stops too
        raise


S = TypeVar("S", bound="Lifecycle")


class Lifecycle:
    """``with`` and ``async with`` over ``start``/``stop`` and ``start_async``/``stop_async``.

    The blocking pair runs on the API's loop, the async pair on the caller's: a subclass
    writes those four, and the statements come from here.
    """

    def start(self: S) -> S:
        """Start on the API's background loop."""
        raise NotImplementedError

    def stop(self) -> object:
        """Stop what ``start`` started."""
        raise NotImplementedError

    async def start_async(self: S) -> S:
        """Start on the caller's event loop."""
        raise NotImplementedError

    async def stop_async(self) -> object:
        """Stop what ``start_async`` started."""
        raise NotImplementedError

    def __enter__(self: S) -> S:
        return self.start()

    def __exit__(
        self, kind: type[BaseException] | None, err: BaseException | None, tb: TracebackType | None
    ) -> None:
        self.stop()

    async def __aenter__(self: S) -> S:
        return await self.start_async()

    async def __aexit__(
        self, kind: type[BaseException] | None, err: BaseException | None, tb: TracebackType | None
    ) -> None:
        await self.stop_async()
