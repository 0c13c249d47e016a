"""A Foxglove WebSocket client for the tests, on ``websockets``' own client, and the bridge.

The client is not ours: ``websockets.sync.client`` does the handshake and the framing; this
module only keeps what the server said (channels, services) and waits for what a test
expects, within deadlines scaled by the run's load.
"""

from __future__ import annotations

import json
import struct
import time
from collections.abc import Callable
from typing import Any

from tests.support.load import scaled
from tests.support.procs import Proc, start_cli

V1, SDK = "foxglove.websocket.v1", "foxglove.sdk.v1"
_HEAD = struct.Struct("<BIQ")
_CALL = struct.Struct("<BIII")


def start_bridge(env: dict[str, str], *args: str) -> tuple[Proc, str]:
    """``rostools bridge ARGS --port 0 -F json``, once it listens; with its URL."""
    proc = start_cli("bridge", "--port", "0", "-F", "json", *args, env=env)
    line = proc.expect(r'"event": ?"listening"', 30)
    return proc, json.loads(line)["url"]


class Client:
    """One connection, and what the server has told it so far."""

    def __init__(self, url: str, subprotocol: str = V1, **kwargs: Any) -> None:
        from websockets.sync.client import connect

        # entered as a context manager, which websockets 17.1 asks of a direct connection
        self.ws = connect(url, subprotocols=[subprotocol], open_timeout=scaled(10), **kwargs)  # type: ignore[list-item]
        self.ws.__enter__()
        self.server_info: dict[str, Any] = {}
        self.channels: dict[str, dict[str, Any]] = {}
        self.services: dict[str, dict[str, Any]] = {}
        #: Every JSON message, in order (advertisements too).
        self.seen: list[dict[str, Any]] = []
        #: subscription id -> (timestamp, payload) of each message received
        self.messages: dict[int, list[tuple[int, bytes]]] = {}
        self.binary: list[bytes] = []  # binary messages other than message data
        self._ids = iter(range(1, 1 << 30))
        self._looked = 0  # messages of ``seen`` that ``wait`` has looked at
        self.wait(lambda m: m.get("op") == "serverInfo")

    def close(self) -> None:
        """Close the connection."""
        self.ws.close()

    def __enter__(self) -> Client:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def send(self, message: dict[str, Any] | str | bytes) -> None:
        """Send a JSON object, or a text or binary message as it is."""
        self.ws.send(json.dumps(message) if isinstance(message, dict) else message)

    def _take(self, raw: str | bytes) -> dict[str, Any] | None:
        if isinstance(raw, bytes):
            if raw[0] == 1 and len(raw) >= _HEAD.size:
                _, sub, stamp = _HEAD.unpack_from(raw)
                self.messages.setdefault(sub, []).append((stamp, raw[_HEAD.size :]))
            else:
                self.binary.append(raw)
            return None
        message: dict[str, Any] = json.loads(raw)
        self.seen.append(message)
        op = message.get("op")
        if op == "serverInfo":
            self.server_info = message
        elif op == "advertise":
            self.channels.update({c["topic"]: c for c in message["channels"]})
        elif op == "unadvertise":
            gone = set(message["channelIds"])
            self.channels = {t: c for t, c in self.channels.items() if c["id"] not in gone}
        elif op == "advertiseServices":
            self.services.update({s["name"]: s for s in message["services"]})
        elif op == "unadvertiseServices":
            gone = set(message["serviceIds"])
            self.services = {n: s for n, s in self.services.items() if s["id"] not in gone}
        return message

    def poll(self, until: Callable[[], bool], timeout: float = 15.0, what: str = "") -> None:
        """Read messages until ``until()`` holds; AssertionError after ``timeout`` (scaled)."""
        deadline = time.monotonic() + scaled(timeout)
        while not until():
            left = deadline - time.monotonic()
            if left <= 0:
                tail = self.seen[-5:]
                raise AssertionError(f"no {what or 'such message'} in time; last: {tail}")
            try:
                self._take(self.ws.recv(timeout=min(left, 0.5)))
            except TimeoutError:
                continue

    def wait(
        self, match: Callable[[dict[str, Any]], bool], timeout: float = 15.0
    ) -> dict[str, Any]:
        """The next JSON message that ``match``es (from those not yet looked at by ``wait``)."""
        found: list[dict[str, Any]] = []

        def seen() -> bool:
            while not found and self._looked < len(self.seen):
                message = self.seen[self._looked]
                self._looked += 1
                if match(message):
                    found.append(message)
            return bool(found)

        self.poll(seen, timeout, "matching message")
        return found[0]

    def channel(self, topic: str, timeout: float = 15.0) -> dict[str, Any]:
        """The channel of ``topic``, once advertised."""
        self.poll(lambda: topic in self.channels, timeout, f"advertisement of {topic}")
        return self.channels[topic]

    def subscribe(self, topic: str, **extra: Any) -> int:
        """Subscribe to ``topic``; the subscription id."""
        sub_id = next(self._ids)
        channel = self.channel(topic)["id"]
        self.send(
            {"op": "subscribe", "subscriptions": [{"id": sub_id, "channelId": channel, **extra}]}
        )
        return sub_id

    def receive(
        self, sub_id: int, count: int = 1, timeout: float = 15.0
    ) -> list[tuple[int, bytes]]:
        """The first ``count`` messages of a subscription."""
        got = self.messages.setdefault(sub_id, [])
        self.poll(lambda: len(got) >= count, timeout, f"{count} messages on subscription {sub_id}")
        return got[:count]

    def status(self, text: str, timeout: float = 15.0) -> dict[str, Any]:
        """The next status message whose text contains ``text``."""
        return self.wait(lambda m: m.get("op") == "status" and text in m["message"], timeout)

    def call(self, service: str, request: bytes, call_id: int = 1) -> None:
        """Send a ros1 service call request."""
        service_id = self.services[service]["id"]
        self.send(_CALL.pack(2, service_id, call_id, 4) + b"ros1" + request)

    def responses(self) -> list[tuple[int, int, bytes]]:
        """(service id, call id, payload) of each service response received."""
        out = []
        for raw in self.binary:
            if raw[0] == 3:
                _, service, call, length = _CALL.unpack_from(raw)
                out.append((service, call, raw[_CALL.size + length :]))
        return out


def ros_string(text: str) -> bytes:
    """A std_msgs/String's bytes."""
    data = text.encode()
    return struct.pack("<I", len(data)) + data
