"""A node's end: a task that lost its cancellation holds neither the process nor the master."""

from __future__ import annotations

import asyncio
import contextlib
import threading
from types import SimpleNamespace
from typing import Any

import pytest

from rostools.node import mastercalls, watch
from rostools.node.session import run_bounded


def test_a_task_deaf_to_cancellation_does_not_hold_the_command() -> None:
    # asyncio.run waited for it forever: the player of a CI run outlived its SIGINT that way.
    released = threading.Event()

    async def stubborn() -> None:
        while not released.is_set():
            # What Python 3.11's wait_for does when the call had just finished:
            with contextlib.suppress(asyncio.CancelledError):
                await asyncio.sleep(0.01)

    async def main() -> int:
        asyncio.get_running_loop().create_task(stubborn())
        await asyncio.sleep(0)
        return 7

    result: list[int] = []
    thread = threading.Thread(target=lambda: result.append(run_bounded(main())), daemon=True)
    thread.start()
    thread.join(5)
    released.set()  # lets a loop that did hang end, so that nothing leaks into other tests
    assert not thread.is_alive(), "the command waited for a task that ignores cancellation"
    assert result == [7]


def test_a_stopped_watch_never_registers_again(monkeypatch: pytest.MonkeyPatch) -> None:
    calls: list[str] = []
    node = SimpleNamespace(
        name="/n", master_uri="http://127.0.0.1:1/", uri="http://127.0.0.1:2/",
        publishers={"/t": SimpleNamespace(type=SimpleNamespace(type="std_msgs/String"))},
        subscribers={}, services={}, master_lost=False, notify=lambda notice: None,
        master=mastercalls.LiveMaster("http://127.0.0.1:1/", "/n"),
    )  # fmt: skip
    w = watch.MasterWatch(node)

    async def fake_call(uri: str, method: str, params: Any, timeout: float) -> Any:
        calls.append(method)
        if method == "lookupNode":  # the node closes while its lookup is answered ...
            w.stop()
            with contextlib.suppress(asyncio.CancelledError):  # ... and wait_for loses the
                await asyncio.sleep(0)  # cancellation
            return [-1, "unknown node [/n]", ""]  # the node has just unregistered
        return [[1, "", 1]]

    monkeypatch.setattr(mastercalls, "call", fake_call)
    monkeypatch.setattr(watch, "WATCH_PERIOD", 0.0)

    async def main() -> None:
        w.start()
        await asyncio.wait_for(asyncio.shield(w._task), 2)  # type: ignore[arg-type]

    asyncio.run(main())
    assert calls == ["lookupNode"], "a closed node was registered with the master again"
