"""A measuring receiver: a Foxglove WebSocket client, or a direct TCPROS subscriber.

usage: bridge_client.py ws URL SUBPROTOCOL TOPIC WARMUP SECONDS [READ_BPS]
       bridge_client.py direct - - TOPIC WARMUP SECONDS
It counts the messages and bytes that arrive in SECONDS after WARMUP, and each one's delay
(receive wall time minus the stamp at bytes 4..12 of the message). READ_BPS reads no faster
than that many bytes a second (a slow client). Prints one JSON line with what it saw.
"""

from __future__ import annotations

import asyncio
import json
import os
import struct
import sys
import time

STAMP = struct.Struct("<II")


class Meter:
    """Counts what arrives inside the window."""

    def __init__(self, warmup: float, seconds: float) -> None:
        self.start = time.monotonic() + warmup
        self.end = self.start + seconds
        self.messages = self.bytes = 0
        self.delays: list[float] = []

    def take(self, payload: bytes | memoryview) -> None:
        now = time.monotonic()
        if self.start <= now < self.end:
            secs, nsecs = STAMP.unpack_from(payload, 4)
            self.delays.append((time.time_ns() - secs * 1_000_000_000 - nsecs) / 1e6)
            self.messages += 1
            self.bytes += len(payload)

    def report(self) -> dict[str, float]:
        span = self.end - self.start
        d = sorted(self.delays) or [float("nan")]
        return {
            "messages_s": self.messages / span,
            "mb_s": self.bytes / span / 1e6,
            "p50_ms": d[len(d) // 2],
            "p99_ms": d[min(len(d) - 1, int(len(d) * 0.99))],
        }


async def websocket(url: str, proto: str, topic: str, meter: Meter, read_bps: float) -> None:
    from websockets.asyncio.client import connect

    async with connect(url, subprotocols=[proto], max_size=None, compression=None) as ws:  # type: ignore[list-item]
        subscribed = False
        async for raw in ws:
            if isinstance(raw, str):
                msg = json.loads(raw)
                if msg.get("op") == "advertise" and not subscribed:
                    for ch in msg["channels"]:
                        if ch["topic"] == topic:
                            sub = {
                                "op": "subscribe",
                                "subscriptions": [{"id": 1, "channelId": ch["id"]}],
                            }
                            await ws.send(json.dumps(sub))
                            subscribed = True
                continue
            if raw[0] == 1:
                meter.take(memoryview(raw)[13:])
                if read_bps:
                    await asyncio.sleep(len(raw) / read_bps)
            if time.monotonic() >= meter.end:
                return


async def direct(topic: str, meter: Meter) -> None:
    from rostools.node.node import LiveNode

    node = await LiveNode("bench_direct", os.environ["ROS_MASTER_URI"], anonymous_name=True).start()
    await node.subscribe(topic, lambda frames, conn, now: [meter.take(f) for f in frames])
    await asyncio.sleep(meter.end - time.monotonic())
    await node.close()


def main() -> None:
    kind, url, proto, topic, warmup, seconds = sys.argv[1:7]
    read_bps = float(sys.argv[7]) if len(sys.argv) > 7 else 0.0
    meter = Meter(float(warmup), float(seconds))
    if kind == "ws":
        asyncio.run(websocket(url, proto, topic, meter, read_bps))
    else:
        asyncio.run(direct(topic, meter))
    print(json.dumps(meter.report()), flush=True)


if __name__ == "__main__":
    main()
