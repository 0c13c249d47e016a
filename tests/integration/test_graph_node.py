"""Our nodes on our master, in one process: the transport's behaviour end to end."""

from __future__ import annotations

import asyncio
import hashlib
import socket
import struct
import xmlrpc.client
from collections.abc import Awaitable, Callable, Iterator
from typing import Any

import pytest

from rostools.master.server import MasterThread
from rostools.msgs.codec import Codec
from rostools.msgs.store import BuiltinSource, TypeStore
from rostools.msgs.topictype import TopicType
from rostools.node.node import LiveNode
from rostools.wire.header import encode_header

STORE = TypeStore([BuiltinSource()])
CODEC = Codec.of(STORE)
STRING = TopicType.of(STORE, "std_msgs/String")
IMAGE = TopicType.of(STORE, "sensor_msgs/Image")
POINT = TopicType.of(STORE, "geometry_msgs/PointStamped")


@pytest.fixture(scope="module")
def master() -> Iterator[MasterThread]:
    with MasterThread() as m:
        yield m


def run(coro: Callable[[], Awaitable[Any]]) -> Any:
    return asyncio.run(asyncio.wait_for(coro(), 30))


async def until(predicate: Callable[[], bool], timeout: float = 5.0) -> None:
    deadline = asyncio.get_running_loop().time() + timeout
    while not predicate():
        if asyncio.get_running_loop().time() > deadline:
            raise AssertionError("condition not reached")
        await asyncio.sleep(0.01)


def string(text: str) -> bytes:
    return CODEC.message_class("std_msgs/String")(text).serialize()


def test_publish_subscribe_latch_and_seq(master: MasterThread) -> None:
    async def main() -> None:
        pub_node = await LiveNode("pub", master.uri).start()
        sub_node = await LiveNode("sub", master.uri, anonymous_name=True).start()
        try:
            latched = await pub_node.advertise("/latched", STRING, latch=True)
            latched.publish(string("kept"))
            points = await pub_node.advertise("points", POINT)
            got: list[Any] = []
            sub = await sub_node.subscribe("/latched", lambda f, c, t: got.extend(f))
            await until(lambda: len(got) == 1)
            assert CODEC.decode("std_msgs/String", got[0]).data == "kept"
            assert sub.type.type == "std_msgs/String"  # learnt from the publisher
            seqs: list[int] = []
            await sub_node.subscribe(
                "/points", lambda f, c, t: seqs.extend(struct.unpack_from("<I", x)[0] for x in f)
            )
            await until(lambda: points.subscriber_count == 1)
            msg = CODEC.message_class("geometry_msgs/PointStamped")()
            msg.header.seq = 999  # type: ignore[attr-defined]
            for _ in range(3):
                points.publish(msg.serialize())
            await until(lambda: len(seqs) == 3)
            assert seqs == [1, 2, 3]  # rewritten as rospy does
        finally:
            await sub_node.close()
            await pub_node.close()

    run(main)


def test_slave_api(master: MasterThread) -> None:
    async def main() -> None:
        node = await LiveNode("api_node", master.uri).start()
        other = await LiveNode("peer", master.uri).start()
        try:
            await node.advertise("/out", STRING)
            await other.subscribe("/out", lambda f, c, t: None)
            await until(lambda: len(node.publishers["/out"].links) == 1)
            api = xmlrpc.client.ServerProxy(node.uri)
            loop = asyncio.get_running_loop()

            def calls() -> dict[str, Any]:
                return {
                    "pid": api.getPid("/x"),
                    "pubs": api.getPublications("/x"),
                    "info": api.getBusInfo("/x"),
                    "stats": api.getBusStats("/x"),
                    "uri": api.getMasterUri("/x"),
                    "bad": api.requestTopic("/x", "/nope", [["TCPROS"]]),
                    "udp": api.requestTopic("/x", "/out", [["UDPROS"]]),
                    "arity": api.getPid("/x", 1),
                }

            answers = await loop.run_in_executor(None, calls)
            assert answers["pid"][0] == 1
            assert answers["pubs"] == [1, "publications", [["/out", "std_msgs/String"]]]
            [conn] = answers["info"][2]
            assert conn[1:6] == ["/peer", "o", "TCPROS", "/out", True]
            assert answers["stats"][0] == 1
            assert answers["uri"] == [1, master.uri, master.uri]
            assert answers["bad"] == [-1, "Not a publisher of [/nope]", []]
            assert answers["udp"] == [0, "no supported protocol implementations", []]
            assert answers["arity"] == [-1, "Error: bad call arity", -1]  # rospy's error value
            await loop.run_in_executor(None, api.shutdown, "/x", "test")
            assert node.shutdown_requested.is_set() and node.shutdown_reason == "test"
        finally:
            await other.close()
            await node.close()

    run(main)


def test_hostile_peers_do_not_break_a_node(master: MasterThread) -> None:
    async def main() -> None:
        node = await LiveNode("victim", master.uri).start()
        try:
            pub = await node.advertise("/t", STRING)
            port = node.tcpros_port

            def attack(payload: bytes) -> bytes:
                with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
                    s.sendall(payload)
                    s.shutdown(socket.SHUT_WR)
                    chunks = []
                    while data := s.recv(65536):
                        chunks.append(data)
                    return b"".join(chunks)

            loop = asyncio.get_running_loop()
            garbage = await loop.run_in_executor(None, attack, b"\x10\x00\x00\x00garbage-garbage!")
            assert garbage == b""  # closed, nothing said
            huge = await loop.run_in_executor(
                None, attack, struct.pack("<I", 2_000_000_000) + b"xx"
            )
            assert huge == b""
            wrong = encode_header(
                {"callerid": "/evil", "topic": "/t", "md5sum": "0" * 32, "type": "a/B"}
            )
            answer = await loop.run_in_executor(None, attack, wrong)
            assert b"error=topic types do not match" in answer
            unknown = encode_header({"callerid": "/evil", "topic": "/none", "md5sum": "*"})
            assert b"is not a publisher of [/none]" in await loop.run_in_executor(
                None, attack, unknown
            )
            # And it still works for a well-behaved subscriber.
            peer = await LiveNode("good", master.uri).start()
            got: list[Any] = []
            await peer.subscribe("/t", lambda f, c, t: got.extend(f))
            await until(lambda: pub.subscriber_count == 1)
            pub.publish(string("fine"))
            await until(lambda: len(got) == 1)
            await peer.close()
        finally:
            await node.close()

    run(main)


def test_big_messages_arrive_byte_exact(master: MasterThread) -> None:
    async def main() -> None:
        a = await LiveNode("img_pub", master.uri).start()
        b = await LiveNode("img_sub", master.uri).start()
        try:
            pub = await a.advertise("/image", IMAGE)
            got: list[bytes] = []
            await b.subscribe("/image", lambda f, c, t: got.extend(bytes(x) for x in f))
            await until(lambda: pub.subscriber_count == 1)
            img = CODEC.message_class("sensor_msgs/Image")(
                height=512, width=683, encoding="rgb8", step=683 * 3, data=bytes(range(256)) * 4098
            )
            wire = [img.serialize() for _ in range(5)]
            for w in wire:
                pub.publish(w)
            await until(lambda: len(got) == 5, 10)
            # Byte-exact but for header.seq, which the publisher numbers 1, 2, ...
            assert [hashlib.md5(g[4:]).digest() for g in got] == [
                hashlib.md5(w[4:]).digest() for w in wire
            ]
            assert [struct.unpack_from("<I", g)[0] for g in got] == [1, 2, 3, 4, 5]
        finally:
            await b.close()
            await a.close()

    run(main)


def test_slow_subscriber_does_not_stall_a_fast_one(master: MasterThread) -> None:
    async def main() -> None:
        pub_node = await LiveNode("fan", master.uri).start()
        fast = await LiveNode("fast", master.uri).start()
        try:
            pub = await pub_node.advertise("/firehose", STRING, queue_size=10)
            got: list[int] = []
            await fast.subscribe("/firehose", lambda f, c, t: got.append(len(f)))
            # A subscriber that says hello and then never reads.
            slow = socket.create_connection(("127.0.0.1", pub_node.tcpros_port))
            slow.sendall(encode_header({"callerid": "/slow", "topic": "/firehose", "md5sum": "*"}))
            await until(lambda: pub.subscriber_count == 2)
            payload = string("x" * 60000)
            for _ in range(400):  # 24 MB: far beyond what the slow socket can buffer
                pub.publish(payload)
                await asyncio.sleep(0)
            await until(lambda: sum(got) == 400, 15)
            slow_link = next(link for link in pub.links if link.peer == "/slow")
            assert slow_link.dropped > 0 and len(slow_link.backlog) <= 10
            slow.close()
        finally:
            await fast.close()
            await pub_node.close()

    run(main)


def test_subscriber_follows_publishers_that_come_and_go(master: MasterThread) -> None:
    async def main() -> None:
        sub_node = await LiveNode("follower", master.uri).start()
        try:
            got: list[str] = []
            await sub_node.subscribe(
                "/come_go",
                lambda f, c, t: got.extend(CODEC.decode("std_msgs/String", x).data for x in f),
            )
            for round_ in range(3):
                pub_node = await LiveNode("comer", master.uri, anonymous_name=True).start()
                pub = await pub_node.advertise("/come_go", STRING)
                await until(lambda p=pub: p.subscriber_count == 1)  # type: ignore[misc]
                pub.publish(string(f"round {round_}"))
                await until(lambda r=round_: f"round {r}" in got)  # type: ignore[misc]
                await pub_node.close()
            assert got == ["round 0", "round 1", "round 2"]
        finally:
            await sub_node.close()

    run(main)
