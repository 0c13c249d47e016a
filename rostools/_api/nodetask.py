"""A node of its own running one task, from a ``with`` or an ``async with``.

The recordings, the snapshot recorder and the bridge are one each. The node is listed with
``exiting`` from its start (its task is finished as the process ends, however it ends), and
``_finish`` stops the task, waits for it and closes the node.
"""

from __future__ import annotations

import asyncio
from collections.abc import Callable, Coroutine
from typing import Any, TypeVar

from rostools._api import exiting, loop
from rostools._api.asyncnode import default_master_uri
from rostools.node.node import LiveNode

T = TypeVar("T", bound="NodeTask")


class NodeTask(loop.Lifecycle):
    """One task on a node of its own, on the API's loop or the caller's."""

    #: The node's name (made anonymous).
    node_name = "rostools"

    def __init__(self, master_uri: str | None) -> None:
        self.master_uri = master_uri
        self._node: LiveNode | None = None
        self._stop: asyncio.Event | None = None
        self._task: asyncio.Task[None] | None = None
        self._on_api_loop = False

    @property
    def running(self) -> bool:
        """Whether its task runs."""
        return self._task is not None and not self._task.done()

    async def _open_node(self) -> LiveNode:
        """The node, started (not yet the task's)."""
        node = LiveNode(self.node_name, self.master_uri or default_master_uri(),
                        anonymous_name=True)  # fmt: skip
        await node.start()
        return node

    def _launch(
        self, node: LiveNode, run: Callable[[asyncio.Event], Coroutine[Any, Any, None]]
    ) -> None:
        """Run ``run(stop)`` on ``node`` until ``_finish``, and at the process's exit."""
        self._node, self._stop = node, asyncio.Event()
        exiting.track(node, self._finish)
        self._task = asyncio.get_running_loop().create_task(run(self._stop))

    async def _finish(self) -> None:
        """Stop the task, wait for it (its error is raised), close the node."""
        if self._stop is not None:
            self._stop.set()
        try:
            if self._task is not None:
                await self._task
        finally:
            if self._node is not None:
                node, self._node = self._node, None
                try:
                    await node.close()
                finally:
                    exiting.forget(node)

    def _start_on_api_loop(self: T) -> T:
        self._on_api_loop = True
        exiting.take_sigterm()  # here, on the caller's thread: the start runs on the loop's
        return loop.run(self.start_async())

    def _stop_on_api_loop(self) -> None:
        if self._on_api_loop and self._node is not None:
            loop.run(self._finish())
