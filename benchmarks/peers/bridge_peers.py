"""The processes of benchmarks/bench_bridge.py besides the bridge and the publisher.

Usage:
  bridge_peers.py reader URL TOPIC [--slow BYTES_PER_S]
      a Foxglove WebSocket client: subscribes to TOPIC's channel and reads every message
      (--slow: sleeps after each so that it reads BYTES_PER_S on average)
  bridge_peers.py rosbridge URL TOPIC TYPE COMPRESSION
      a rosbridge v2 client (rosbridge_server's or rostools bridge's): subscribes to TOPIC
      with COMPRESSION (none: JSON, cbor, cbor-raw) and reads every message
  bridge_peers.py direct MASTER TOPIC
      a TCPROS subscriber (rostools' node, raw frames): the ceiling
  bridge_peers.py foxglove MASTER TOPIC TYPE
      foxglove-sdk's (Rust) WebSocket server, fed each raw frame a TCPROS subscriber reads

A reader (reader, direct) prints "ready" after its first message, then waits for one line on
stdin, "START_NS END_NS" (wall clock), counts what arrives in that window, and prints one JSON
line once it is over: {"messages", "bytes", "duplicates", "delays_ns": [...]}. "bytes" counts
ROS message bytes (the WebSocket message's 13-byte prefix left out); a message whose stamp is
not newer than the last one's is a duplicate, counted apart. A delay is the arrival's wall-clock
time less the message's header.stamp, which every message here has at bytes 4..12. A rosbridge
reader counts the WebSocket message's bytes, and reads the stamp without decoding the rest of a
JSON message (its head: a client's CPU must not hold the server back); a CBOR message is
decoded whole (cbor2, in C), cbor-raw's stamp read from its TCPROS bytes.
The foxglove server prints {"port": N} once it listens and is subscribed, and runs until
SIGINT.
"""

from __future__ import annotations

import asyncio
import json
import os
import re
import signal
import struct
import sys
import time
from typing import Any

_STAMP = struct.Struct("<II")
#: The Foxglove MessageData prefix: opcode, subscription id, receive time.
PREFIX = 13
#: header.stamp in a rosbridge JSON message's head (rosbridge_server writes spaces, we do not).
_JSON_STAMP = re.compile(rb'"stamp":\s*\{\s*"secs":\s*(\d+),\s*"nsecs":\s*(\d+)')
_HEAD = 512
READ_TIMEOUT = 60.0


class Window:
    """What one reader saw in the window the harness gives it."""

    def __init__(self) -> None:
        self.start = 0
        self.end = 0
        self.given = asyncio.get_running_loop().create_future()
        self.messages = 0
        self.bytes = 0
        self.delays: list[int] = []
        self.duplicates = 0
        self._last = -1
        asyncio.get_running_loop().run_in_executor(None, self._read_stdin)

    def _read_stdin(self) -> None:
        line = sys.stdin.readline().split()
        loop = self.given.get_loop()
        loop.call_soon_threadsafe(self._set, line)

    def _set(self, line: list[str]) -> None:
        if self.given.done():
            return
        if len(line) == 2:
            self.start, self.end = int(line[0]), int(line[1])
            self.given.set_result(True)
        else:
            self.given.set_result(False)  # the harness is gone

    def note(self, now: int, payload: Any, size: int) -> bool:
        """Count a message that arrived at ``now``; whether the window is over."""
        secs, nsecs = _STAMP.unpack_from(payload, 4)
        return self.note_stamp(now, secs * 1_000_000_000 + nsecs, size)

    def note_stamp(self, now: int, stamp: int, size: int) -> bool:
        """Count a message stamped ``stamp`` that arrived at ``now``; whether the window is over."""
        if self.given.done() and self.start <= now < self.end:
            if stamp <= self._last:  # the publisher's stamps only grow: sent twice
                self.duplicates += 1
                return False
            self._last = stamp
            self.messages += 1
            self.bytes += size
            self.delays.append(now - stamp)
        return self.given.done() and now >= self.end

    def report(self) -> None:
        """The JSON line."""
        out = {
            "messages": self.messages,
            "bytes": self.bytes,
            "duplicates": self.duplicates,
            "delays_ns": self.delays,
        }
        print(json.dumps(out), flush=True)


async def reader(url: str, topic: str, slow: float) -> None:
    """A WebSocket client of either server (it offers both subprotocol names)."""
    from websockets.asyncio.client import connect

    window = Window()
    async with connect(
        url,
        subprotocols=["foxglove.sdk.v1", "foxglove.websocket.v1"],  # type: ignore[list-item]
        max_size=None,
        compression=None,
        max_queue=1 if slow else 16,
        open_timeout=30,
    ) as ws:
        channel = None
        while channel is None:
            text = await asyncio.wait_for(ws.recv(), READ_TIMEOUT)
            if isinstance(text, str):
                msg = json.loads(text)
                if msg.get("op") == "advertise":
                    found = [c["id"] for c in msg["channels"] if c["topic"] == topic]
                    channel = found[0] if found else None
        sub = {"op": "subscribe", "subscriptions": [{"id": 1, "channelId": channel}]}
        await ws.send(json.dumps(sub))
        ready = False
        while True:
            timeout = READ_TIMEOUT
            if window.given.done():
                if not window.given.result():
                    return
                timeout = max(window.end - time.time_ns(), 0) / 1e9 + 0.1
            try:
                data = await asyncio.wait_for(ws.recv(), timeout)
            except TimeoutError:
                if window.given.done():
                    break
                raise
            now = time.time_ns()
            if isinstance(data, str) or data[0] != 1:
                continue
            if not ready:
                print("ready", flush=True)
                ready = True
            if window.note(now, memoryview(data)[PREFIX:], len(data) - PREFIX):
                break
            if slow:
                await asyncio.sleep(len(data) / slow)
    window.report()


def rosbridge_stamp(data: bytes, compression: str) -> int:
    """header.stamp (ns) of one rosbridge ``publish`` message."""
    if compression == "none":
        found = _JSON_STAMP.search(data, 0, _HEAD)
        if found is None:
            stamp = json.loads(data)["msg"]["header"]["stamp"]
            return int(stamp["secs"]) * 1_000_000_000 + int(stamp["nsecs"])
        return int(found[1]) * 1_000_000_000 + int(found[2])
    import cbor2

    msg = cbor2.loads(data)["msg"]
    if compression == "cbor-raw":
        secs, nsecs = _STAMP.unpack_from(msg["bytes"], 4)
        return int(secs) * 1_000_000_000 + int(nsecs)
    stamp = msg["header"]["stamp"]
    return int(stamp["secs"]) * 1_000_000_000 + int(stamp["nsecs"])


async def rosbridge(url: str, topic: str, type_name: str, compression: str) -> None:
    """A rosbridge v2 client of either server: one subscription, every message read."""
    from websockets.asyncio.client import connect

    window = Window()
    sub: dict[str, Any] = {"op": "subscribe", "id": "bench", "topic": topic, "type": type_name}
    if compression != "none":
        sub["compression"] = compression
    async with connect(url, max_size=None, compression=None, open_timeout=30) as ws:
        await ws.send(json.dumps(sub))
        ready = False
        while True:
            timeout = READ_TIMEOUT
            if window.given.done():
                if not window.given.result():
                    return
                timeout = max(window.end - time.time_ns(), 0) / 1e9 + 0.1
            try:
                data = await asyncio.wait_for(ws.recv(decode=False), timeout)
            except TimeoutError:
                if window.given.done():
                    break
                raise
            now = time.time_ns()
            if b"publish" not in data[:64]:  # a status message: kept for the harness's error
                print(bytes(data[:300]).decode(errors="replace"), file=sys.stderr, flush=True)
                continue
            if not ready:
                print("ready", flush=True)
                ready = True
            if window.note_stamp(now, rosbridge_stamp(data, compression), len(data)):
                break
    window.report()


async def direct(master: str, topic: str) -> None:
    """The ceiling: a plain TCPROS subscriber, stamps read from the raw frames."""
    from rostools.node.node import LiveNode

    window = Window()
    done = asyncio.get_running_loop().create_future()
    ready = [False]

    def on_frames(frames: list[Any], conn: object, _: float) -> None:
        now = time.time_ns()
        if not ready[0]:
            print("ready", flush=True)
            ready[0] = True
        for frame in frames:
            if window.note(now, frame, len(frame)) and not done.done():
                done.set_result(None)

    node = await LiveNode(f"bench_direct_{os.getpid()}", master).start()
    await node.subscribe(topic, on_frames)
    await window.given
    if window.given.result():
        await asyncio.wait_for(done, max(window.end - time.time_ns(), 0) / 1e9 + READ_TIMEOUT)
    await node.close()
    window.report()


async def fox(master: str, topic: str, type_name: str) -> None:
    """foxglove-sdk's server, fed the raw bytes of each message, stamped on arrival."""
    import foxglove

    from rostools.msgs.store import TypeStore
    from rostools.msgs.topictype import TopicType
    from rostools.node.node import LiveNode

    kind = TopicType.of(TypeStore.default(), type_name)
    server = foxglove.start_server(
        name="foxglove-sdk (bench)", host="127.0.0.1", port=0, supported_encodings=["ros1"]
    )
    schema = foxglove.Schema(name=kind.type, encoding="ros1msg", data=kind.definition.encode())
    channel = foxglove.Channel(topic, schema=schema, message_encoding="ros1")
    log = channel.base.log

    def on_frames(frames: list[Any], conn: object, _: float) -> None:
        now = time.time_ns()
        for frame in frames:
            # The SDK takes bytes only: a big frame (a read-only view) is copied once here.
            log(frame if isinstance(frame, bytes) else bytes(frame), now, None)

    node = await LiveNode(f"bench_foxglove_{os.getpid()}", master).start()
    await node.subscribe(topic, on_frames, kind)
    stop = asyncio.Event()
    asyncio.get_running_loop().add_signal_handler(signal.SIGINT, stop.set)
    asyncio.get_running_loop().add_signal_handler(signal.SIGTERM, stop.set)
    print(json.dumps({"port": server.port}), flush=True)
    await stop.wait()
    await node.close()
    server.stop()


def main(argv: list[str]) -> None:
    """Run one role."""
    role = argv[0]
    if role == "reader":
        slow = float(argv[4]) if len(argv) > 4 and argv[3] == "--slow" else 0.0
        asyncio.run(reader(argv[1], argv[2], slow))
    elif role == "rosbridge":
        asyncio.run(rosbridge(argv[1], argv[2], argv[3], argv[4]))
    elif role == "direct":
        asyncio.run(direct(argv[1], argv[2]))
    elif role == "foxglove":
        asyncio.run(fox(argv[1], argv[2], argv[3]))
    else:
        sys.exit(f"unknown role {role}")


if __name__ == "__main__":
    main(sys.argv[1:])
