"""The API's nodes at the end of the process: each unregisters, as a rospy node does.

Every node the API starts (``Node``, ``AsyncNode``, the default node of the module-level
functions, a recording's or a snapshot's node) is listed here from its start to its close.
When the process ends with nodes still open (the script's end, an exception, Ctrl-C), an
``atexit`` handler closes each: on its own loop if that loop still runs (the API's background
loop does), else by blocking calls to the master from the exiting thread.

SIGTERM ends a Python process without ``atexit``. If the program has no SIGTERM handler of
its own when its main thread starts a node, the API installs one that closes the open nodes
and then ends the process by SIGTERM, as the default would have: the process's exit status
and what runs before it ends are Python's default's, plus the unregistering.
"""

from __future__ import annotations

import asyncio
import atexit
import concurrent.futures
import contextlib
import logging
import os
import signal
import threading
import time
from collections.abc import Callable, Coroutine
from types import FrameType
from typing import Any

from rostools.node.node import LiveNode
from rostools.rosgraph.masterapi import XmlRpcNode, master_timeout

log = logging.getLogger(__name__)

#: How long closing the open nodes may take beyond the master's timeout (every master call's
#: bound, ``ROSTOOLS_MASTER_TIMEOUT``) before the process leaves anyway.
EXIT_GRACE = 1.0

Closer = Callable[[], Coroutine[Any, Any, object]]

#: Every node started and not closed: the loop it runs on, and how it closes there.
_open: dict[LiveNode, tuple[asyncio.AbstractEventLoop, Closer]] = {}
_at_exit_registered = False
_sigterm_decided = False
# A forked child has none of its parent's nodes (nor the threads that run their loops).
os.register_at_fork(after_in_child=_open.clear)


def track(node: LiveNode, close: Closer) -> None:
    """List ``node``, just started on the running loop, until ``forget``.

    ``close()`` is what closes it on that loop (the node's owner's close, which forgets it).
    """
    global _at_exit_registered
    _open[node] = (asyncio.get_running_loop(), close)
    if not _at_exit_registered:
        _at_exit_registered = True
        atexit.register(_at_exit)
    take_sigterm()


def forget(node: LiveNode) -> None:
    """``node`` is closed (or closing): the end of the process need not close it."""
    _open.pop(node, None)


def take_sigterm() -> None:
    """On the main thread, once: handle SIGTERM if the program has not chosen what it does."""
    global _sigterm_decided
    if _sigterm_decided or threading.current_thread() is not threading.main_thread():
        return
    _sigterm_decided = True
    if signal.getsignal(signal.SIGTERM) is signal.SIG_DFL:
        signal.signal(signal.SIGTERM, _on_sigterm)


def close_all(timeout: float | None = None) -> None:
    """Close every open node within ``timeout`` s in all (default: the master's, and a second)."""
    deadline = time.monotonic() + (master_timeout() + EXIT_GRACE if timeout is None else timeout)
    try:
        here: asyncio.AbstractEventLoop | None = asyncio.get_running_loop()
    except RuntimeError:
        here = None
    waits: list[concurrent.futures.Future[object]] = []
    for node, (loop, close) in list(_open.items()):
        # a loop that still runs closes its node; this thread's own loop cannot (a SIGTERM
        # came while it ran), nor can one that has ended
        if loop is not here and loop.is_running():
            coro = close()
            try:
                waits.append(asyncio.run_coroutine_threadsafe(coro, loop))
                continue
            except RuntimeError:  # it closed in between
                coro.close()
        _unregister(node, deadline)
    for waiting in waits:
        with contextlib.suppress(Exception):
            waiting.result(max(0.0, deadline - time.monotonic()))


def _unregister(node: LiveNode, deadline: float) -> None:
    """Undo ``node``'s registrations by blocking calls (its loop no longer runs)."""
    forget(node)
    try:
        calls = node.unregister_calls()
        if not calls:
            return
        proxy = XmlRpcNode(node.master_uri, node.name, max(0.1, deadline - time.monotonic()))
        for method, args in calls:
            proxy.limit(max(0.1, deadline - time.monotonic()))
            proxy.raw(method, *args)
        proxy.http.close()
    except Exception as err:  # noqa: BLE001 - leaving anyway; the master may be gone
        log.debug("unregistering %s from %s failed: %s", node.name, node.master_uri, err)


def _at_exit() -> None:
    with contextlib.suppress(KeyboardInterrupt):  # Ctrl-C again: leave at once
        close_all()


def _on_sigterm(signum: int, frame: FrameType | None) -> None:
    signal.signal(signal.SIGTERM, signal.SIG_DFL)  # a second SIGTERM ends it at once
    with contextlib.suppress(Exception):
        close_all()
    os.kill(os.getpid(), signal.SIGTERM)
    os._exit(128 + signal.SIGTERM)  # not reached: the signal's default ends the process
