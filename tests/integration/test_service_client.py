"""The asyncio service client against a scripted server on loopback: no master, no ROS."""

from __future__ import annotations

import asyncio
import struct
from collections.abc import Awaitable, Callable
from typing import Any

import pytest

from rostools.errors import RostoolsError, ServiceError, TimeoutExpired
from rostools.msgs.topictype import ServiceType
from rostools.node.service import EAGER_READS, ServiceClient
from rostools.wire.header import encode_header

TYPE = ServiceType("test_msgs/Echo", "0123456789abcdef0123456789abcdef")


class _Owner:
    """What the client asks of its node: a name, and the master's answer to lookupService."""

    def __init__(self, port: int) -> None:
        self.name = "/tester"
        self.port = port
        self.master = self

    async def lookup_service(self, name: str) -> str:
        return f"rosrpc://127.0.0.1:{self.port}"


async def _read_frame(reader: asyncio.StreamReader) -> bytes:
    (length,) = struct.unpack("<I", await reader.readexactly(4))
    return await reader.readexactly(length)


#: How the server answers a request: the response payload, or None to stay silent.
Answer = Callable[[bytes], Awaitable[bytes | None]]


async def _serve(answer: Answer) -> tuple[asyncio.Server, int, list[int]]:
    """A service that echoes requests back (or as ``answer`` says); counts connections."""
    connections: list[int] = []

    async def client(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        connections.append(1)
        try:
            await _read_frame(reader)
            writer.write(encode_header({"md5sum": TYPE.md5sum, "type": TYPE.type}))
            while True:
                request = await _read_frame(reader)
                payload = await answer(request)
                if payload is None:
                    continue
                if payload == b"refuse":
                    writer.write(b"\x00" + struct.pack("<I", 4) + b"nope")
                else:
                    writer.write(b"\x01" + struct.pack("<I", len(payload)) + payload)
        except (asyncio.IncompleteReadError, ConnectionError):
            pass
        finally:
            writer.close()

    server = await asyncio.start_server(client, "127.0.0.1", 0)
    return server, server.sockets[0].getsockname()[1], connections


async def _echo(request: bytes) -> bytes | None:
    if request == b"silent":
        return None
    if request.startswith(b"slow"):
        await asyncio.sleep(0.05)
    return request


def test_pipelined_calls_each_get_their_own_response() -> None:
    async def main() -> None:
        server, port, connections = await _serve(_echo)
        client = ServiceClient(_Owner(port), "/echo", TYPE, persistent=True)  # type: ignore[arg-type]
        requests = [b"slow0", *(f"r{i}".encode() for i in range(1, 20))]
        # Every call is in flight at once, the first one slowest: the earlier client kept one
        # waiter per connection, so all but one waited out their timeout.
        answers = await asyncio.gather(*(client.call(r, timeout=2) for r in requests))
        assert answers == requests
        assert len(connections) == 1  # the first calls shared the connection being opened
        client.close()
        server.close()

    asyncio.run(main())


def test_one_timer_for_many_calls() -> None:
    async def main() -> None:
        server, port, _ = await _serve(_echo)
        client = ServiceClient(_Owner(port), "/echo", TYPE, persistent=True)  # type: ignore[arg-type]
        await client.call(b"first")
        loop = asyncio.get_running_loop()
        timers = 0
        call_at = loop.call_at

        def counting(*args: Any, **kwargs: Any) -> asyncio.TimerHandle:
            nonlocal timers
            timers += 1
            return call_at(*args, **kwargs)

        loop.call_at = counting  # type: ignore[method-assign]
        for i in range(50):
            assert await client.call(str(i).encode()) == str(i).encode()
        loop.call_at = call_at  # type: ignore[method-assign]
        # A timer per call was a fifth of a fast call's cost.
        assert timers <= 1
        client.close()
        server.close()

    asyncio.run(main())


def test_timeout_refusal_and_reconnect() -> None:
    async def main() -> None:
        server, port, connections = await _serve(_echo)
        client = ServiceClient(_Owner(port), "/echo", TYPE, persistent=True)  # type: ignore[arg-type]
        assert await client.call(b"a") == b"a"
        with pytest.raises(ServiceError, match="nope"):
            await client.call(b"refuse")
        assert await client.call(b"b") == b"b"  # a refusal keeps the connection
        assert len(connections) == 1
        start = asyncio.get_running_loop().time()
        with pytest.raises(TimeoutExpired, match=r"within 0\.2 s"):
            await client.call(b"silent", timeout=0.2)
        assert asyncio.get_running_loop().time() - start < 1.0
        # The silent connection was dropped; the next call connects anew.
        assert await client.call(b"c") == b"c"
        assert len(connections) == 2
        # A call cancelled by its caller: its response is dropped, the next call gets its own.
        task = asyncio.ensure_future(client.call(b"slow-cancelled"))
        await asyncio.sleep(0.01)
        task.cancel()
        assert await client.call(b"d") == b"d"
        server.close()
        await server.wait_closed()
        client.close()
        with pytest.raises(RostoolsError):
            await client.call(b"e", timeout=1)

    asyncio.run(main())


def test_non_persistent_connects_per_call() -> None:
    async def main() -> None:
        server, port, connections = await _serve(_echo)
        client = ServiceClient(_Owner(port), "/echo", TYPE)  # type: ignore[arg-type]
        assert [await client.call(b"x"), await client.call(b"y")] == [b"x", b"y"]
        assert len(connections) == 2
        server.close()

    asyncio.run(main())


def test_back_to_back_calls_let_other_tasks_run() -> None:
    async def main() -> None:
        server, port, _ = await _serve(_echo)
        client = ServiceClient(_Owner(port), "/echo", TYPE, persistent=True)  # type: ignore[arg-type]
        ticks = 0

        async def other() -> None:
            nonlocal ticks
            while True:
                ticks += 1
                await asyncio.sleep(0)

        task = asyncio.ensure_future(other())
        await asyncio.sleep(0)
        # Responses read as soon as the request is sent never wait for the loop; every
        # EAGER_READS-th call does, so other tasks still run.
        for _ in range(4 * EAGER_READS):
            await client.call(b"x")
        assert ticks >= 4
        task.cancel()
        client.close()
        server.close()

    asyncio.run(main())
