"""Running a command as a short-lived node: start, stop on Ctrl-C/SIGTERM/shutdown, clean up.

``run_node(main, ...)`` gives ``main`` a started ``LiveNode`` and a ``stop`` event that is set by
SIGINT, SIGTERM, SIGHUP or a ``shutdown`` call (``rosnode kill``); whatever happens, the node
unregisters from the master before the process exits.
"""

from __future__ import annotations

import asyncio
import contextlib
import signal
from collections.abc import Awaitable, Callable, Coroutine
from typing import Any, TypeVar

from rostools.errors import RostoolsError
from rostools.node.listen import raise_descriptor_limit
from rostools.node.node import LiveNode
from rostools.node.notice import Notice

T = TypeVar("T")


async def first(*aws: Awaitable[object], timeout: float | None = None) -> int | None:
    """Wait for the first of several awaitables; its index, or None on timeout.

    The others are cancelled.
    """
    tasks = [asyncio.ensure_future(a) for a in aws]
    try:
        done, _ = await asyncio.wait(tasks, timeout=timeout, return_when=asyncio.FIRST_COMPLETED)
    finally:
        for task in tasks:
            if not task.done():
                task.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await task
    for i, task in enumerate(tasks):
        if task in done:
            return i
    return None


#: Signals that stop a command cleanly: Ctrl-C, ``kill``, and a closed terminal or SSH session.
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


def run_node(
    main: Callable[[LiveNode, asyncio.Event], Awaitable[T]],
    master_uri: str,
    name: str = "rostools",
    anonymous_name: bool = True,
    remappings: dict[str, str] | None = None,
    notify: Callable[[Notice], None] | None = None,
) -> T:
    """Run ``main(node, stop)`` on a fresh event loop; the node is closed afterwards.

    ``notify`` receives the node's notices (default: one line each on stderr).

    The stop signals stay caught until the node has unregistered, so a second Ctrl-C during
    shutdown neither interrupts the unregistering nor prints a traceback.
    """
    raise_descriptor_limit()  # record -a of a thousand topics holds a socket per topic

    async def runner() -> T:
        node = LiveNode(name, master_uri, anonymous_name=anonymous_name, remappings=remappings)
        if notify is not None:
            node.notify = notify
        try:
            await node.start()
        except OSError as err:
            raise RostoolsError(f"cannot open the node's sockets: {err.strerror or err}") from err
        loop = asyncio.get_running_loop()
        stop = asyncio.Event()
        for sig in STOP_SIGNALS:
            loop.add_signal_handler(sig, stop.set)

        async def on_shutdown() -> None:
            await node.shutdown_requested.wait()
            stop.set()

        watcher = loop.create_task(on_shutdown())
        try:
            return await main(node, stop)
        finally:
            watcher.cancel()
            await node.close()
            for sig in STOP_SIGNALS:
                loop.remove_signal_handler(sig)

    return run_bounded(runner())


#: How long the tasks left after a command's ``main`` get to end once cancelled (s).
LEFTOVER_GRACE = 1.0


def run_bounded(main: Coroutine[Any, Any, T]) -> T:
    """``asyncio.run(main)``, except that the tasks left after it get ``LEFTOVER_GRACE``.

    ``asyncio.run`` waits for them without a limit: a task that lost its cancellation
    (Python 3.11's ``wait_for`` can) would hold a finished command, its stop signals no
    longer caught, until something killed it.
    """
    loop = asyncio.new_event_loop()
    asyncio.set_event_loop(loop)
    try:
        return loop.run_until_complete(main)
    finally:
        try:
            rest = asyncio.all_tasks(loop)
            for task in rest:
                task.cancel()
            if rest:
                loop.run_until_complete(asyncio.wait(rest, timeout=LEFTOVER_GRACE))
            for task in rest:
                if not task.done():  # abandoned on purpose: no "destroyed but pending" at exit
                    task._log_destroy_pending = False  # type: ignore[attr-defined]
            loop.run_until_complete(loop.shutdown_asyncgens())
            loop.run_until_complete(loop.shutdown_default_executor())
        finally:
            asyncio.set_event_loop(None)
            loop.close()
