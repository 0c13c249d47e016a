"""The client of ``trigger_snapshot``: ask a snapshot recorder for a file, wait until complete.

It listens on the recorder's ``~written`` before calling, so it cannot miss the file's
announcement, and matches it by the name the answer gave. A recorder without ``~written``
(rosbag_snapshot's own, which answers once the file is written) is done when it answers.
"""

from __future__ import annotations

import asyncio
import json
import struct
from collections.abc import Callable
from typing import Any

from rostools.bag.live.snapshot_srv import SnapshotRequest, TriggerError, decode_answer
from rostools.errors import NotFoundError, UnreachableError
from rostools.msgs.topictype import ServiceType
from rostools.msgs.wellknown import TRIGGER, TRIGGER_SNAPSHOT
from rostools.names import namespace
from rostools.node.connection import Frame, InboundConnection
from rostools.node.node import LiveNode
from rostools.node.service import ServiceClient
from rostools.node.session import first

#: How long the client waits to be connected to ``~written`` before it calls.
CONNECT_TIMEOUT = 5.0


async def find_recorder(node: LiveNode, target: str | None) -> tuple[str, str]:
    """The ``trigger_snapshot`` service and the node serving it, by node name or namespace."""
    if target is not None:
        name = node.resolve(target)
        return namespace(name).rstrip("/") + "/trigger_snapshot", name
    service = node.resolve("trigger_snapshot")
    _, _, services = await node.master.system_state()
    for srv, providers in services:
        if srv == service and providers:
            return service, str(providers[0])
    raise NotFoundError(
        f"no snapshot recorder serves {service}",
        hint="start one with 'rostools bag snapshot', or name its node",
    )


async def call(node: LiveNode, service: str, kind: ServiceType, request: bytes) -> str:
    """Call one of the recorder's services; its message, or ``TriggerError``."""
    ok, message = decode_answer(await ServiceClient(node, service, kind).call(request))
    if not ok:
        raise TriggerError(f"{service}: {message}")
    return message


async def request_snapshot(
    node: LiveNode,
    target: str | None,
    request: Callable[[], SnapshotRequest],
    stop: asyncio.Event | None = None,
    on_named: Callable[[str], None] | None = None,
) -> dict[str, Any]:
    """Trigger a snapshot and wait until its file is complete; what it holds (``summary``).

    ``request`` is called just before the service is (its window starts from the time it
    reads), so finding the recorder and connecting to ``~written`` take nothing from the
    buffer: a small buffer at a high rate spans less than a second. When ``stop`` is set
    before the file is complete (Ctrl-C on ``--continue``), the recorder is asked to end its
    open-ended files, and the wait goes on.
    """
    service, recorder = await find_recorder(node, target)
    written: dict[str, dict[str, Any]] = {}
    arrived = asyncio.Event()

    def on_frames(frames: list[Frame], conn: InboundConnection, now: float) -> None:
        for data in frames:
            (size,) = struct.unpack_from("<I", data)
            summary = json.loads(bytes(data[4 : 4 + size]))
            written[str(summary.get("name"))] = summary
        arrived.set()

    topic = recorder + "/written"
    pubs, _, _ = await node.master.system_state()
    listening = any(t == topic for t, _ in pubs)
    if listening:
        await _connected(node, topic, on_frames)
    asked = request()
    name = await call(node, service, TRIGGER_SNAPSHOT, asked.encode())
    name = name or asked.filename
    if on_named is not None:
        on_named(name)
    if not listening:
        return {"name": name}
    stopped = stop if stop is not None else asyncio.Event()
    while name not in written:
        if await first(arrived.wait(), stopped.wait()) == 1 and name not in written:
            await call(node, recorder + "/stop", TRIGGER, b"")
            stopped = asyncio.Event()  # asked once; now only wait
        arrived.clear()
    return written[name]


async def _connected(
    node: LiveNode, topic: str, on_frames: Callable[[list[Frame], InboundConnection, float], None]
) -> None:
    """Subscribe to ``topic`` and wait until a publisher is connected."""
    sub = await node.subscribe(topic, on_frames)
    loop = asyncio.get_running_loop()
    deadline = loop.time() + CONNECT_TIMEOUT
    while not sub.connections:
        if loop.time() > deadline:
            raise UnreachableError(f"cannot connect to {topic} to learn when the file is written")
        await asyncio.sleep(0.01)
