"""What a TCPROS connection costs: little while it is idle, nothing once it has closed.

Each test opens many connections to a node and reads the node's resident memory from
/proc/PID/status (deltas, never absolutes). Before issue 24, every connection took a 256 KiB
buffer when it was accepted, kept it while idle, and left it behind when it closed.
"""

from __future__ import annotations

import asyncio
import collections
import signal
import struct
import sys
import threading
import time
import xmlrpc.client
from collections.abc import Iterator
from pathlib import Path

import pytest

from rostools.master.server import MasterThread
from rostools.msgs.store import BuiltinSource, TypeStore
from rostools.msgs.topictype import TopicType
from rostools.node import connection, mastercalls, subscriber
from rostools.node.node import LiveNode
from rostools.node.notice import Notice
from rostools.wire.tcpros import subscriber_header
from tests.support.load import scaled
from tests.support.procs import Proc, free_port, linked, publishers, start_cli, wait_for

STRING = TopicType.of(TypeStore([BuiltinSource()]), "std_msgs/String")
#: Connections per test: each cost 256 KiB (1,000: +257 MB) before; a few KB now.
MANY = 1000
#: MB a node may grow by for MANY connections, and keep after they closed.
BOUND_MB = 40

Streams = list[tuple[asyncio.StreamReader, asyncio.StreamWriter]]


def rss_mb(pid: int) -> float:
    """A process's resident memory now."""
    status = Path(f"/proc/{pid}/status").read_text()
    return int(status.split("VmRSS:")[1].split()[0]) / 1024


def tcpros_port(master_uri: str, node: str, topic: str) -> int:
    """The TCPROS port of ``node``, which publishes ``topic``."""
    master = xmlrpc.client.ServerProxy(master_uri)
    # the core answers before its /rosout has registered: wait for the node, not the master
    wait_for(lambda: master.lookupNode("/t", node)[0] == 1, 30, f"{node} registered")
    api = master.lookupNode("/t", node)[2]
    _, _, (_, _, port) = xmlrpc.client.ServerProxy(api).requestTopic("/t", topic, [["TCPROS"]])
    return int(port)


def links(master_uri: str, node: str, topic: str) -> int:
    """How many subscribers of ``topic``, which ``node`` publishes, it says are connected."""
    return len(linked(master_uri, node, topic))


async def connect(port: int, count: int, first: bytes = b"", batch: int = 50) -> Streams:
    """``count`` connections to ``port``, ``batch`` at a time; each sends ``first`` at once."""
    streams: Streams = []

    async def one() -> None:
        reader, writer = await asyncio.open_connection("127.0.0.1", port)
        if first:
            writer.write(first)
        streams.append((reader, writer))

    for done in range(0, count, batch):
        await asyncio.gather(*(one() for _ in range(min(batch, count - done))))
    return streams


def hold(port: int, count: int, first: bytes, while_open: object, batch: int = 50) -> None:
    """Open ``count`` connections that send ``first``, call ``while_open()``, close them."""

    async def main() -> None:
        streams = await connect(port, count, first, batch)
        await asyncio.get_running_loop().run_in_executor(None, while_open)  # type: ignore[arg-type]
        for _, writer in streams:
            writer.close()

    asyncio.run(main())


@pytest.mark.parametrize("speaks", [True, False], ids=["subscribers", "silent"])
def test_connections_cost_the_core_little_and_leave_nothing(
    rostools_master: str, cli_env: dict[str, str], speaks: bool
) -> None:
    # the defect: 1,000 subscribers of /rosout_agg took the core from 29 to 286 MB, and it
    # stayed at 286 MB once they had gone; 1,000 that said nothing cost as much until the
    # handshake deadline closed them, and left it behind too
    core_pid = _core_pid(rostools_master)
    port = tcpros_port(rostools_master, "/rosout", "/rosout_agg")
    header = subscriber_header("/idle", "/rosout_agg", "*", "*", "", False) if speaks else b""
    time.sleep(0.5)
    before = rss_mb(core_pid)
    during: list[float] = []

    def measure() -> None:
        if speaks:
            wait_for(lambda: links(rostools_master, "/rosout", "/rosout_agg") >= MANY, 60, "links")
        else:
            time.sleep(connection.PENDING_GRACE + 1)  # all but the newest are dropped
        during.append(rss_mb(core_pid))

    hold(port, MANY, header, measure)
    wait_for(lambda: links(rostools_master, "/rosout", "/rosout_agg") == 0, 30, "links closed")
    time.sleep(0.5)
    after = rss_mb(core_pid)
    assert during[0] - before < BOUND_MB, (before, during, after)
    assert after - before < BOUND_MB, (before, during, after)


def _core_pid(master_uri: str) -> int:
    """The PID of the process serving ``master_uri`` (the master answers getPid)."""
    code, _, pid = xmlrpc.client.ServerProxy(master_uri).getPid("/t")
    assert code == 1
    return int(pid)


def test_hostile_subscribers_cost_a_publisher_little(
    rostools_master: str, cli_env: dict[str, str]
) -> None:
    # the defect: each subscriber that announced a huge frame after its header got a 1 MiB
    # buffer for it and a 256 KiB one for reading (300 of them: +375 MB); a subscriber sends
    # nothing after its header, and what it sends now goes nowhere
    pub = start_cli("topic", "pub", "-r", "1", "/target", "std_msgs/String", "data: x", env=cli_env)
    try:
        wait_for(lambda: publishers(rostools_master, "/target"), 15, "/target published")
        [name] = publishers(rostools_master, "/target")
        port = tcpros_port(rostools_master, name, "/target")
        hostile = subscriber_header("/evil", "/target", "*", "*", "", False)
        hostile += struct.pack("<I", 999_999_999) + b"x" * 1000
        time.sleep(0.5)
        before = rss_mb(pub.pid)
        count = 300
        during: list[float] = []

        def measure() -> None:
            wait_for(lambda: links(rostools_master, name, "/target") >= count, 60, "links")
            time.sleep(0.5)  # the junk after each header has arrived
            during.append(rss_mb(pub.pid))

        hold(port, count, hostile, measure)
        wait_for(lambda: links(rostools_master, name, "/target") == 0, 30, "links closed")
        after = rss_mb(pub.pid)
        assert during[0] - before < BOUND_MB, (before, during, after)
        assert after - before < BOUND_MB, (before, during, after)
        assert pub.popen.poll() is None  # still publishing
    finally:
        pub.stop()


@pytest.fixture
def master() -> Iterator[MasterThread]:
    with MasterThread() as m:
        yield m


def _closed(reader: asyncio.StreamReader) -> bool:
    """Whether the server closed this connection (end of stream, or reset)."""
    return reader.at_eof() or reader.exception() is not None


def test_silent_connections_past_the_limit_drop_the_oldest(
    master: MasterThread, monkeypatch: pytest.MonkeyPatch
) -> None:
    # the defect: no limit; every silent connection held its buffers until the handshake
    # deadline, so a flood of them cost what the flood chose
    monkeypatch.setattr(connection, "HANDSHAKE_TIMEOUT", 60.0)  # the limit, not the deadline
    extra = 50

    async def main() -> tuple[set[int], list[bytes]]:
        node = await LiveNode("flooded", master.uri).start()
        listener = await LiveNode("listener", master.uri).start()
        try:
            pub = await node.advertise("/f", STRING)
            streams: Streams = []
            for _ in range(connection.MAX_PENDING + extra):  # in order: oldest first
                streams.append(await asyncio.open_connection("127.0.0.1", node.tcpros_port))
            for _ in range(100):
                if sum(_closed(r) for r, _ in streams) >= extra:
                    break
                await asyncio.sleep(0.05)
            await asyncio.sleep(0.2)  # more would be dropped by now, if it were wrong
            closed = {i for i, (r, _) in enumerate(streams) if _closed(r)}
            # a real subscriber, whose header comes at once, still gets through
            got: list[bytes] = []
            await listener.subscribe("/f", lambda frames, conn, t: got.extend(map(bytes, frames)))
            for _ in range(100):
                if pub.subscriber_count:
                    break
                await asyncio.sleep(0.05)
            pub.publish(struct.pack("<I", 2) + b"hi")
            for _ in range(100):
                if got:
                    break
                await asyncio.sleep(0.05)
            for _, writer in streams:
                writer.close()
            return closed, got
        finally:
            await listener.close()
            await node.close()

    closed, got = asyncio.run(main())
    assert closed == set(range(extra))
    assert got == [struct.pack("<I", 2) + b"hi"]


def test_a_burst_of_subscribers_past_the_limit_all_get_through(master: MasterThread) -> None:
    """Real subscribers send their header at once; a burst of them is accepted faster than
    the headers are read, and none may be taken for silent."""
    count = 3 * connection.MAX_PENDING

    async def main() -> int:
        node = await LiveNode("popular", master.uri).start()
        try:
            pub = await node.advertise("/p", STRING)
            header = subscriber_header("/many", "/p", "*", "*", "", False)
            # from another thread and loop, as from another process: the node accepts while
            # the subscribers write
            loop = asyncio.get_running_loop()
            counted = threading.Event()  # the subscribers stay until they have been counted
            hold_open = loop.run_in_executor(
                None, hold, node.tcpros_port, count, header, lambda: counted.wait(600), count
            )
            # a bound, not a pace: 300 connections on a loaded machine took more than 10 s
            deadline = time.monotonic() + scaled(60)
            while pub.subscriber_count < count and time.monotonic() < deadline:
                await asyncio.sleep(0.05)
            await asyncio.sleep(connection.PENDING_GRACE + 0.5)  # past any drop
            connected = pub.subscriber_count
            counted.set()
            await hold_open
            return connected
        finally:
            await node.close()

    assert asyncio.run(main()) == count


# --- a publisher of many topics that goes away ----------------------------------------------

TOPICS = 50
#: A node that publishes TOPICS topics, says "ready", and waits to be killed.
MANY_TOPICS = f"""
import asyncio, sys
from rostools.msgs.store import BuiltinSource, TypeStore
from rostools.msgs.topictype import TopicType
from rostools.node.node import LiveNode

async def main():
    node = await LiveNode("/many", sys.argv[1]).start()
    string = TopicType.of(TypeStore([BuiltinSource()]), "std_msgs/String")
    for i in range({TOPICS}):
        await node.advertise(f"/many_{{i}}", string)
    print("ready", flush=True)
    await asyncio.sleep(3600)

asyncio.run(main())
"""


def _subscribe_all(
    master_uri: str, monkeypatch: pytest.MonkeyPatch, while_subscribed: object
) -> tuple[list[Notice], collections.Counter[str]]:
    """Subscribe to every /many_N; the notices until each topic has one, and the calls made."""
    calls: collections.Counter[str] = collections.Counter()
    real = mastercalls.call

    async def counted(uri: str, method: str, params: tuple[object, ...], *more: float) -> object:
        calls[method] += 1
        return await real(uri, method, params, *more)

    monkeypatch.setattr(mastercalls, "call", counted)

    async def main() -> list[Notice]:
        node = await LiveNode("/watcher", master_uri).start()
        notices: list[Notice] = []
        node.notify = notices.append
        try:
            subs = [
                await node.subscribe(f"/many_{i}", lambda frames, conn, t: None)
                for i in range(TOPICS)
            ]
            loop = asyncio.get_running_loop()
            await loop.run_in_executor(None, while_subscribed, subs)  # type: ignore[arg-type]
            # a publisher that closed its connections is reported once it has been unreachable
            # for subscriber.REPORT_AFTER_DROP
            deadline = time.monotonic() + scaled(subscriber.REPORT_AFTER_DROP + 10)
            while len({n.fields["topic"] for n in notices}) < TOPICS:
                if time.monotonic() > deadline:
                    break
                await asyncio.sleep(0.05)
        finally:
            await node.close()
        return notices

    return asyncio.run(main()), calls


def test_a_publisher_that_dies_is_named_without_asking_the_master(
    master: MasterThread, monkeypatch: pytest.MonkeyPatch
) -> None:
    # the defect: every topic of a publisher that died asked the master for getSystemState to
    # name it, all at once; for 1,000 topics a recorder went from 40 MB to 280 MB
    pub = Proc([sys.executable, "-c", MANY_TOPICS, master.uri])
    try:
        assert pub.popen.stdout is not None
        assert pub.popen.stdout.readline().strip() == b"ready"

        def kill_when_connected(subs: list[subscriber.Subscriber]) -> None:
            # its name comes with its header: a connection that has none yet is not enough
            wait_for(lambda: all(s.names for s in subs), 30, "every topic's header")
            pub.signal(signal.SIGKILL)  # it dies registered: the master still lists it

        notices, calls = _subscribe_all(master.uri, monkeypatch, kill_when_connected)
    finally:
        pub.stop()
    assert sorted(n.fields["topic"] for n in notices) == sorted(f"/many_{i}" for i in range(TOPICS))
    assert {n.fields["node"] for n in notices} == {"/many"}
    assert calls["getSystemState"] == 0, calls


def test_name_lookups_of_one_unreachable_publisher_are_shared(
    master: MasterThread, monkeypatch: pytest.MonkeyPatch
) -> None:
    # the defect: each of its topics looked the publisher up on its own, all at once
    dead = f"http://127.0.0.1:{free_port()}/"
    # Sharing, not the names' expiry, is under test: on a loaded machine the 50 reports can
    # spread over more than NAME_KEEP, and a fresh cache keeps an earlier test's names out.
    monkeypatch.setattr(subscriber, "NAME_KEEP", 3600.0)
    monkeypatch.setattr(subscriber, "_names", {})
    with xmlrpc.client.ServerProxy(master.uri) as proxy:
        for i in range(TOPICS):
            code, message, _ = proxy.registerPublisher(
                "/ghost", f"/many_{i}", "std_msgs/String", dead
            )
            assert code == 1, message
    notices, calls = _subscribe_all(master.uri, monkeypatch, lambda subs: None)
    assert len(notices) == TOPICS
    assert {(n.fields["node"], n.fields["uri"]) for n in notices} == {("/ghost", dead)}
    assert calls["getSystemState"] == 1, calls
