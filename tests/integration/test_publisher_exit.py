"""A publisher on its way out is not reported as unreachable; one that stays unreachable is.

roscpp, exiting, unregisters its topics, closes its connections, and until the master's
``publisherUpdate`` reaches a subscriber refuses each topic ("received a connection for a
nonexistent topic"). A recorder of a thousand topics printed a line for each of them.
"""

from __future__ import annotations

import asyncio
import socket
import struct
import xmlrpc.client
from collections.abc import Callable

import pytest

from rostools.master.server import MasterThread
from rostools.node import subscriber
from rostools.node.node import LiveNode
from rostools.node.notice import Notice
from rostools.wire.header import encode_header
from tests.support.fakepeer import FakePublisher, frame, valid_header
from tests.support.load import scaled

TOPIC = "/leaving"
REFUSAL = f"received a connection for a nonexistent topic [{TOPIC}]"


def leaving(served: list[socket.socket]) -> Callable[[socket.socket], None]:
    """A publisher that sends one message and closes, then refuses the topic."""

    def send(sock: socket.socket) -> None:
        served.append(sock)
        if len(served) == 1:
            sock.sendall(valid_header(TOPIC) + frame(struct.pack("<I", 2) + b"hi"))
        else:
            sock.sendall(encode_header({"error": REFUSAL}))
        sock.close()

    return send


async def until(done: Callable[[], bool], what: str, within: float = 20) -> None:
    """Until ``done()``, polled; AssertionError after ``within`` s (scaled by the load)."""
    deadline = asyncio.get_running_loop().time() + scaled(within)
    while not done():
        assert asyncio.get_running_loop().time() < deadline, f"no {what}"
        await asyncio.sleep(0.02)


def run(
    master_uri: str, served: list[socket.socket], unregister: Callable[[], None] | None
) -> tuple[list[Notice], list[bytes]]:
    """Subscribe to TOPIC until the refusals have begun (and, with ``unregister``, until the
    master has told the subscriber it is gone); the notices, and the frames received."""

    async def main() -> tuple[list[Notice], list[bytes]]:
        node = await LiveNode("/recorder", master_uri).start()
        notices: list[Notice] = []
        node.notify = notices.append
        got: list[bytes] = []
        try:
            sub = await node.subscribe(
                TOPIC, lambda frames, conn, t: got.extend(map(bytes, frames))
            )
            await until(lambda: len(served) >= 3, "two refusals after the close")
            if unregister is None:
                await until(lambda: bool(notices), "notice")
            else:
                await asyncio.get_running_loop().run_in_executor(None, unregister)
                await until(lambda: not sub.publishers, "publisherUpdate")
        finally:
            await node.close()
        return notices, got

    return asyncio.run(main())


def test_a_publisher_on_its_way_out_is_not_reported(monkeypatch: pytest.MonkeyPatch) -> None:
    # however slow the master's publisherUpdate (a busy machine): here the test's own pace
    monkeypatch.setattr(subscriber, "REPORT_AFTER_DROP", 600.0, raising=False)
    served: list[socket.socket] = []
    with MasterThread() as master, FakePublisher(master.uri, TOPIC, leaving(served)) as fake:

        def unregister() -> None:
            with xmlrpc.client.ServerProxy(master.uri) as proxy:
                proxy.unregisterPublisher(fake.name, TOPIC, fake.uri)

        notices, got = run(master.uri, served, unregister)
    assert got == [struct.pack("<I", 2) + b"hi"]
    assert notices == [], [n.message for n in notices]


def test_a_publisher_that_stays_unreachable_is_reported(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(subscriber, "REPORT_AFTER_DROP", 0.3, raising=False)
    served: list[socket.socket] = []
    with MasterThread() as master, FakePublisher(master.uri, TOPIC, leaving(served)):
        notices, _ = run(master.uri, served, None)
    assert len(notices) == 1, [n.message for n in notices]
    assert notices[0].event == "peer_unreachable" and REFUSAL in notices[0].message, notices[0]
