"""The bridge's per-client queues: latest wins, bounded, counted, and nobody waits on a client."""

from __future__ import annotations

import asyncio
import struct

import pytest

from rostools.web import client as client_mod
from rostools.web.client import Client, Subscription
from rostools.web.params import from_client, leaves, to_client
from rostools.wire import foxglove
from rostools.wire.foxglove import ProtocolError


class Stalled:
    """A socket whose reader never reads: every send waits for good."""

    def __init__(self) -> None:
        self.sent: list[str | bytes] = []
        self.gate = asyncio.Event()

    async def send(self, message: str | bytes) -> None:
        self.sent.append(message)
        await self.gate.wait()


class Quick:
    """A socket that takes everything at once."""

    def __init__(self) -> None:
        self.sent: list[str | bytes] = []

    async def send(self, message: str | bytes) -> None:
        self.sent.append(message)


def test_a_stalled_client_holds_a_bounded_queue_and_counts_its_drops() -> None:
    async def scenario() -> tuple[Client, Subscription, Quick]:
        stalled, quick = Client(Stalled(), "slow", lambda c: None), Quick()
        fine = Client(quick, "fine", lambda c: None)
        big = Subscription(1, 1, "/image")
        small = Subscription(2, 2, "/small")
        stalled.subscriptions.update({1: big, 2: small})
        fine_sub = Subscription(1, 1, "/image")
        fine.subscriptions[1] = fine_sub
        frame = bytes(1024 * 1024)
        for n in range(200):
            stalled.offer(big, n, frame, float(n))  # returns at once: nobody waits
            fine.offer(fine_sub, n, frame, float(n))
            await asyncio.sleep(0)
        stalled.offer(small, 7, b"tiny", 0.0)
        await asyncio.sleep(0.01)
        return stalled, big, quick

    _, big, quick = asyncio.run(scenario())
    assert big.queued_bytes <= client_mod.QUEUE_BYTES
    in_the_socket = 1  # taken by the writer, whose send never returns
    assert big.dropped > 150 and big.dropped + len(big.queue) + in_the_socket == 200
    assert len(quick.sent) == 200  # the other client got every message
    assert struct.unpack_from("<BIQ", quick.sent[5]) == (1, 1, 5)


def test_a_small_topic_takes_its_turn_beside_a_big_one() -> None:
    async def scenario() -> list[int]:
        order: list[int] = []

        class Recording(Quick):
            async def send(self, message: str | bytes) -> None:
                assert isinstance(message, bytes)
                order.append(struct.unpack_from("<I", message, 1)[0])
                await asyncio.sleep(0)

        client = Client(Recording(), "c", lambda c: None)
        big, small = Subscription(1, 1, "/big"), Subscription(2, 2, "/small")
        client.subscriptions.update({1: big, 2: small})
        for n in range(50):
            client.offer(big, n, bytes(1000), 0.0)
        for n in range(3):
            client.offer(small, n, b"s", 0.0)
        for _ in range(20):
            await asyncio.sleep(0)
        return order

    order = asyncio.run(scenario())
    assert order[:6] == [1, 2, 1, 2, 1, 2]  # each waiting topic in turn, not 50 big first


def test_a_throttled_subscription_takes_one_message_an_interval() -> None:
    async def scenario() -> Subscription:
        client = Client(Quick(), "c", lambda c: None)
        sub = Subscription(1, 1, "/t", interval=0.2)
        client.subscriptions[1] = sub
        for n in range(10):
            client.offer(sub, n, b"x", 100.0 + n * 0.1)
        await asyncio.sleep(0.01)
        return sub

    sub = asyncio.run(scenario())
    assert (sub.sent, sub.throttled) == (5, 5)


def test_the_newest_message_is_kept_whatever_its_size() -> None:
    async def scenario() -> Subscription:
        client = Client(Stalled(), "c", lambda c: None)
        sub = Subscription(1, 1, "/cloud")
        client.subscriptions[1] = sub
        client.offer(sub, 1, bytes(16), 0.0)  # taken by the writer, which then stalls
        await asyncio.sleep(0)
        for n in range(3):
            client.offer(sub, 2 + n, bytes(client_mod.QUEUE_BYTES + 1), 0.0)
        return sub

    sub = asyncio.run(scenario())
    assert [stamp for stamp, _ in sub.queue] == [4] and sub.dropped == 2


def test_binary_client_messages_read_or_are_named() -> None:
    data = foxglove.parse_binary(b"\x01\x05\x00\x00\x00abc")
    assert isinstance(data, foxglove.ClientData) and data.channel == 5
    assert bytes(data.payload) == b"abc"
    call = foxglove.parse_binary(struct.pack("<BIII", 2, 3, 4, 4) + b"ros1" + b"req")
    assert isinstance(call, foxglove.CallRequest)
    assert (call.service, call.call, call.encoding, bytes(call.payload)) == (3, 4, "ros1", b"req")
    for junk, words in [
        (b"", "empty"),
        (b"\x01\x00", "shorter than its 5-byte header"),
        (b"\x02\x00\x00", "shorter than its 13-byte header"),
        (struct.pack("<BIII", 2, 1, 1, 9) + b"ros1", "runs past the end"),
        (struct.pack("<BIII", 2, 1, 1, 1) + b"\xff", "not UTF-8"),
        (b"\x07", "unknown binary opcode 7"),
    ]:
        with pytest.raises(ProtocolError, match=words):
            foxglove.parse_binary(junk)


def test_json_client_messages_are_checked_before_use() -> None:
    assert foxglove.parse_json('{"op":"unsubscribe","subscriptionIds":[1]}')["op"] == "unsubscribe"
    for junk, words in [
        ("nope", "not JSON"),
        ("[" * 100_000, "not JSON"),
        ('"op"', "not a JSON object"),
        ('{"op": 5}', "unknown op 5"),
        ('{"op": "subscribe"}', "subscriptions missing"),
        ('{"op": "fetchAsset", "uri": "x", "requestId": true}', "requestId missing"),
    ]:
        with pytest.raises(ProtocolError, match=words):
            foxglove.parse_json(junk)
    with pytest.raises(ProtocolError, match="not an id"):
        foxglove.ids([1, 2**32], "unsubscribe")


def test_parameters_cross_in_both_directions() -> None:
    assert to_client("/a", 1.5) == {"name": "/a", "value": 1.5, "type": "float64"}
    assert to_client("/b", b"\x00\x01") == {"name": "/b", "value": "AAE=", "type": "byte_array"}
    assert to_client("/c", [1.0, 2.0])["type"] == "float64_array"
    assert to_client("/d", float("nan"))["value"] == "nan"
    assert to_client("/e", {"x": [1, "y"]}) == {"name": "/e", "value": {"x": [1, "y"]}}
    assert from_client({"name": "f", "value": 2, "type": "float64"}) == ("/f", 2.0)
    assert from_client({"name": "/g", "value": "AAE=", "type": "byte_array"}) == ("/g", b"\x00\x01")
    for bad, words in [
        ({"value": 1}, "without a name"),
        ({"name": "/h", "value": "!", "type": "byte_array"}, "not base64"),
        ({"name": "/h", "value": True, "type": "float64"}, "a float64 is a number"),
        ({"name": "/h"}, "no value"),
    ]:
        with pytest.raises(ProtocolError, match=words):
            from_client(bad)
    assert leaves("/", {"a": {"b": 1, "c": 2}, "d": 3}) == [("/a/b", 1), ("/a/c", 2), ("/d", 3)]


def test_a_client_that_reads_nothing_is_let_go_past_the_control_limit() -> None:
    async def scenario() -> tuple[Client, list[Client]]:
        gone: list[Client] = []
        client = Client(Stalled(), "flooder", gone.append)
        for n in range(client_mod.MAX_CONTROL + 2):
            client.status(foxglove.ERROR, f"refused {n}")
            if n == 0:
                await asyncio.sleep(0)  # the writer takes the first, and stalls on it
        return client, gone

    client, gone = asyncio.run(scenario())
    assert client.closed and gone == [client]
