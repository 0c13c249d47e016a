"""Peers that lie about sizes, stall, or never finish their handshake: bounded memory, one line."""

from __future__ import annotations

import asyncio
import re
import socket
import struct
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from rostools.master.server import MasterThread
from rostools.msgs.store import BuiltinSource, TypeStore
from rostools.msgs.topictype import TopicType
from rostools.node import connection
from rostools.node.node import LiveNode
from tests.support.fakepeer import FakePublisher, first_frames, frame, valid_header
from tests.support.procs import Proc, start_cli

STRING = TopicType.of(TypeStore([BuiltinSource()]), "std_msgs/String")


@pytest.fixture
def master() -> Iterator[MasterThread]:
    with MasterThread() as m:
        yield m


def peak_rss_mb(proc: Proc, timeout: float) -> float:
    """The peak resident memory of ``proc`` (VmHWM) until it exits, in MB."""
    peak, deadline = 0, time.monotonic() + timeout
    while proc.popen.poll() is None and time.monotonic() < deadline:
        try:
            status = Path(f"/proc/{proc.pid}/status").read_text()
        except OSError:
            break
        if "VmHWM:" not in status:  # exiting: its memory is gone already (seen under load)
            break
        peak = max(peak, int(status.split("VmHWM:")[1].split()[0]))
        time.sleep(0.05)
    return peak / 1024


def test_an_announced_gigabyte_costs_little(rostools_master: str, cli_env: dict[str, str]) -> None:
    # the defect: echo allocated what the length prefix claimed, 981 MB before any data came
    def lie(sock: socket.socket) -> None:
        sock.sendall(valid_header("/huge"))
        time.sleep(0.2)  # a read of its own: the header's limit no longer applies
        sock.sendall(struct.pack("<I", 999_999_999) + b"x" * 20)

    with FakePublisher(rostools_master, "/huge", lie):
        echo = start_cli("topic", "echo", "/huge", "--timeout", "3", env=cli_env)
        try:
            peak = peak_rss_mb(echo, 15)
            assert echo.popen.wait(15) == 5
        finally:
            echo.stop()
    assert peak < 150, f"echo peaked at {peak:.0f} MB"


def test_an_oversized_frame_is_said_once(rostools_master: str, cli_env: dict[str, str]) -> None:
    # the defect: echo printed about 60 reconnect warnings and then only timed out
    def oversized(sock: socket.socket) -> None:
        sock.sendall(valid_header("/over") + struct.pack("<I", 2_000_000_000))

    with FakePublisher(rostools_master, "/over", oversized):
        echo = start_cli("topic", "echo", "/over", "--timeout", "4", env=cli_env)
        try:
            assert echo.popen.wait(20) == 5
            _, err = echo.output()
        finally:
            echo.stop()
    told = [line for line in err.splitlines() if "/fake" in line]
    assert len(told) == 1, err
    assert re.fullmatch(
        r"rostools: dropped the connection from /fake at http://127\.0\.0\.1:\d+/ \(publisher "
        r"of /over\): frame of 2000000000 bytes exceeds the limit of 1000000000",
        told[0],
    ), told


def test_a_big_message_in_the_same_read_as_the_header(master: MasterThread) -> None:
    # the defect: a message over 64 MiB that came in one read with the header was checked
    # against the header's limit and dropped
    size = 64 * 1024 * 1024 + 100
    message = struct.pack("<I", size - 4) + b"m" * (size - 4)

    def send(sock: socket.socket) -> None:
        sock.sendall(valid_header("/big") + frame(message))

    with FakePublisher(master.uri, "/big", send):
        assert [len(f) for f in first_frames(master.uri, "/big", "big_sub")] == [size]


def test_a_peer_that_never_sends_its_header_is_closed(
    master: MasterThread, monkeypatch: pytest.MonkeyPatch
) -> None:
    # the defect: no handshake deadline, and a 4-byte prefix reserved 64 MiB for the header
    monkeypatch.setattr(connection, "HANDSHAKE_TIMEOUT", 0.5)

    async def main() -> tuple[bytes, bytes, float]:
        node = await LiveNode("victim", master.uri).start()
        await node.advertise("/v", STRING)
        loop = asyncio.get_running_loop()
        try:
            silent = socket.create_connection(("127.0.0.1", node.tcpros_port))
            huge = socket.create_connection(("127.0.0.1", node.tcpros_port))
            huge.sendall(struct.pack("<I", 64 * 1024 * 1024))
            for sock in (silent, huge):
                sock.settimeout(5)
            began = time.monotonic()
            closed = await loop.run_in_executor(None, silent.recv, 1)
            waited = time.monotonic() - began
            refused = await loop.run_in_executor(None, huge.recv, 1)
            silent.close()
            huge.close()
        finally:
            await node.close()
        return closed, refused, waited

    closed, refused, waited = asyncio.run(main())
    assert closed == b"" and refused == b""
    assert waited < 3


def test_a_message_that_does_not_decode_is_one_line(
    rostools_master: str, cli_env: dict[str, str]
) -> None:
    # the defect: a zero-length frame made echo fail with "internal error: struct.error"
    def empty(sock: socket.socket) -> None:
        sock.sendall(valid_header("/empty") + frame(b""))

    with FakePublisher(rostools_master, "/empty", empty):
        echo = start_cli("topic", "echo", "/empty", "--timeout", "5", "--strict", env=cli_env)
        try:
            assert echo.popen.wait(20) == 1
            _, err = echo.output()
        finally:
            echo.stop()
    assert err.splitlines()[-1].startswith(
        "rostools: a message on /empty does not decode as std_msgs/String: "
    ), err
    assert "internal error" not in err


def _raw_subscriber(master_uri: str, topic: str, rcvbuf: int | None = None) -> socket.socket:
    """A TCPROS subscription made by hand, past its header: the caller reads, or never does."""
    import xmlrpc.client

    from rostools.wire.tcpros import subscriber_header

    master = xmlrpc.client.ServerProxy(master_uri)
    [[_, [node]]] = [p for p in master.getSystemState("/t")[2][0] if p[0] == topic]
    node_api = master.lookupNode("/t", node)[2]
    _, _, (_, host, port) = xmlrpc.client.ServerProxy(node_api).requestTopic(
        "/raw", topic, [["TCPROS"]]
    )
    sock = socket.socket()
    if rcvbuf is not None:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, rcvbuf)
    sock.connect((host, port))
    sock.sendall(subscriber_header("/raw", topic, "*", "*", "", False))
    (length,) = struct.unpack("<I", sock.recv(4, socket.MSG_WAITALL))
    sock.recv(length, socket.MSG_WAITALL)
    return sock


def _count_frames(sock: socket.socket, seconds: float) -> int:
    """Frames received in ``seconds`` (whole reads; the count of length prefixes seen)."""
    count, pending, deadline = 0, b"", time.monotonic() + seconds
    sock.settimeout(0.2)
    while time.monotonic() < deadline:
        try:
            pending += sock.recv(1 << 20)
        except TimeoutError:
            continue
        while len(pending) >= 4:
            (length,) = struct.unpack_from("<I", pending)
            if len(pending) < 4 + length:
                break
            pending, count = pending[4 + length :], count + 1
    return count


def test_a_stalled_subscriber_costs_the_others_nothing(
    rostools_master: str, cli_env: dict[str, str]
) -> None:
    """A subscriber that never reads: the healthy one keeps its rate, the publisher's memory
    stays bounded by its queue (100 messages of 10 KB), not by how long the stall lasts.
    ``-s`` makes every message a new object, so a queue that kept them all would grow."""
    pub = start_cli(
        "topic",
        "pub",
        "-r",
        "500",
        "-s",
        "/load",
        "sensor_msgs/CompressedImage",
        "{header: {stamp: now}, format: " + "x" * 10_000 + "}",
        env=cli_env,
    )
    try:
        deadline = time.monotonic() + 15
        while True:
            try:
                healthy = _raw_subscriber(rostools_master, "/load")
                break
            except ValueError:  # not registered yet
                assert time.monotonic() < deadline, "the publisher never registered"
                time.sleep(0.1)
        stalled = _raw_subscriber(rostools_master, "/load", rcvbuf=4096)
        # Meanwhile the stalled link fills the kernel's buffers, the transport's (4 MB) and
        # the queue; from then on it costs nothing more.
        _count_frames(healthy, 3.0)
        rss_before = int(Path(f"/proc/{pub.pid}/status").read_text().split("VmRSS:")[1].split()[0])
        received = _count_frames(healthy, 4.0)
        rss_after = int(Path(f"/proc/{pub.pid}/status").read_text().split("VmRSS:")[1].split()[0])
        # 20 MB went to the stalled socket's queue in those 4 s if nothing bounded it.
        assert (rss_after - rss_before) / 1024 < 3, (rss_before, rss_after)
        assert received >= 0.9 * 500 * 4, received
        stalled.close()
        healthy.close()
    finally:
        pub.stop()


def _service_answer(node_uri: str, service: str, request: bytes) -> tuple[int, bytes]:
    """A service call made by hand with ``request`` as its bytes: the ok byte and the payload."""
    import xmlrpc.client

    from rostools.wire.tcpros import service_request_header

    master_uri = xmlrpc.client.ServerProxy(node_uri).getMasterUri("/raw")[2]
    host, port = (
        xmlrpc.client.ServerProxy(master_uri)
        .lookupService("/raw", service)[2][len("rosrpc://") :]
        .split(":")
    )
    with socket.create_connection((host, int(port)), timeout=10) as sock:
        sock.sendall(service_request_header("/raw", service, "*") + frame(request))
        (length,) = struct.unpack("<I", sock.recv(4, socket.MSG_WAITALL))
        sock.recv(length, socket.MSG_WAITALL)  # the server's header
        ok = sock.recv(1, socket.MSG_WAITALL)[0]
        (length,) = struct.unpack("<I", sock.recv(4, socket.MSG_WAITALL))
        return ok, sock.recv(length, socket.MSG_WAITALL)


@pytest.mark.parametrize(
    ("service", "request_bytes"),
    [("std_srvs/SetBool", b""), ("rospy_tutorials/AddTwoInts", b"\x01\x00\x00")],
    ids=["empty", "cut-short"],
)
def test_a_request_that_does_not_decode_is_answered_in_words(
    master: MasterThread, service: str, request_bytes: bytes
) -> None:
    # the defect: the client got Python's text, "unpack_from requires a buffer of at least 1
    # bytes for unpacking 1 bytes at offset 0 (actual buffer size is 0)"
    from rostools import Node

    with Node("served", master_uri=master.uri) as node:
        node.advertise_service("/svc", service, lambda request: {})
        ok, text = _service_answer(node.uri, "/svc", request_bytes)
        assert (ok, text.decode()) == (
            0,
            f"service cannot process request: cannot decode {service}Request: "
            "message is shorter than its type says",
        )
        # and the server serves the next call
        good = b"\x01" if service == "std_srvs/SetBool" else bytes(16)
        assert _service_answer(node.uri, "/svc", good)[0] == 1
