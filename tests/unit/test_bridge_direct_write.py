"""Big messages skip websockets' copies (``DirectWrite``): what a real client gets is the same."""

from __future__ import annotations

import asyncio
import ssl
import subprocess
from pathlib import Path
from typing import Any

import pytest

from rostools.web.client import DIRECT_WRITE, Client, Subscription, frame_header
from rostools.wire import foxglove

#: Around each length form's edges (7-bit, 16-bit, 64-bit) and the direct path's threshold.
SIZES = [0, 1, 112, 113, 65_522, 65_523, DIRECT_WRITE - 1, DIRECT_WRITE, 65_536, 3_000_001]


def _frame(i: int, size: int) -> bytes:
    return bytes((i * 37 + k) % 251 for k in range(min(size, 251))) * (size // 251 + 1)


def _tls(folder: Path) -> tuple[ssl.SSLContext, ssl.SSLContext]:
    """A server's context with a new self-signed certificate, and a client's that trusts it."""
    cert, key = folder / "cert.pem", folder / "key.pem"
    subprocess.run(
        ["openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "1",
         "-subj", "/CN=127.0.0.1", "-addext", "subjectAltName=IP:127.0.0.1",
         "-keyout", str(key), "-out", str(cert)],
        check=True, capture_output=True, timeout=60,
    )  # fmt: skip
    server = ssl.SSLContext(ssl.PROTOCOL_TLS_SERVER)
    server.load_cert_chain(cert, key)
    return server, ssl.create_default_context(cafile=str(cert))


@pytest.mark.parametrize("scheme", ["ws", "wss"])
def test_messages_of_every_size_reach_a_websockets_client_whole_and_in_order(
    scheme: str, tmp_path: Path
) -> None:
    from websockets.asyncio.client import connect
    from websockets.asyncio.server import serve

    server_tls, client_tls = _tls(tmp_path) if scheme == "wss" else (None, None)

    frames = [_frame(i, size)[:size] for i, size in enumerate(SIZES)]
    direct: list[int] = []

    async def scenario() -> tuple[list[str | bytes], bool]:
        done = asyncio.Event()

        async def handler(ws: Any) -> None:
            client = Client(ws, "c", lambda c: None)
            assert client._direct is not None  # a websockets connection is written directly
            send = client._direct.send

            async def counted(head: bytes, frame: Any) -> None:
                direct.append(len(frame))
                await send(head, frame)

            client._direct.send = counted  # type: ignore[method-assign]
            sub = client.subscriptions[7] = Subscription(7, 1, "/t")
            for i, frame in enumerate(frames):
                client.send({"op": "status", "level": 0, "message": f"before {i}"})
                view = memoryview(bytearray(frame)).toreadonly()  # as the intake hands them
                client.offer(sub, i, view if i % 2 else frame, 0.0)
                await asyncio.sleep(0)  # the writer runs between offers
            await done.wait()
            client.close()

        async with serve(handler, "127.0.0.1", 0, compression=None, ssl=server_tls) as server:
            port = server.sockets[0].getsockname()[1]
            url = f"{scheme}://127.0.0.1:{port}"
            got: list[str | bytes] = []
            async with connect(url, max_size=None, compression=None, ssl=client_tls) as ws:
                pong = await ws.ping()  # answered between the data frames
                while sum(isinstance(m, bytes) for m in got) < len(frames):
                    got.append(await asyncio.wait_for(ws.recv(), 30))
                await asyncio.wait_for(pong, 30)
                done.set()
            return got, True

    got, ponged = asyncio.run(scenario())
    data = [m for m in got if isinstance(m, bytes)]
    assert data == [foxglove.message_data(7, i) + f for i, f in enumerate(frames)]
    assert [m for m in got if isinstance(m, str)] == [
        foxglove.dumps({"op": "status", "level": 0, "message": f"before {i}"})
        for i in range(len(frames))
    ]
    assert ponged
    assert direct == [s for s in SIZES if s >= DIRECT_WRITE]  # the rest went through send()


def test_a_frame_header_uses_the_shortest_length_form() -> None:
    assert frame_header(125) == b"\x82\x7d"
    assert frame_header(126) == b"\x82\x7e\x00\x7e"
    assert frame_header(65_535) == b"\x82\x7e\xff\xff"
    assert frame_header(65_536) == b"\x82\x7f" + (65_536).to_bytes(8, "big")
    assert frame_header(125, text=True) == b"\x81\x7d"


def test_a_closed_connection_is_not_written_directly() -> None:
    from websockets.asyncio.client import connect
    from websockets.asyncio.server import serve

    async def scenario() -> tuple[bool, bool]:
        states: list[bool] = []
        closed = asyncio.Event()

        async def handler(ws: Any) -> None:
            client = Client(ws, "c", lambda c: None)
            assert client._direct is not None
            states.append(client._direct.ready())
            await ws.wait_closed()
            states.append(client._direct.ready())
            client.close()
            closed.set()

        async with serve(handler, "127.0.0.1", 0, compression=None) as server:
            port = server.sockets[0].getsockname()[1]
            async with connect(f"ws://127.0.0.1:{port}", compression=None):
                pass
            await asyncio.wait_for(closed.wait(), 30)
        return states[0], states[1]

    while_open, once_closed = asyncio.run(scenario())
    assert while_open and not once_closed
