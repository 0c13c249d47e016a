"""The bundled master over real sockets: keep-alive, hostile clients, notifications."""

from __future__ import annotations

import http.client
import socket
import threading
import time
import xmlrpc.client
from collections.abc import Iterator
from typing import Any

import pytest

from rostools.master.server import MasterThread
from rostools.node import rpc as graph_xmlrpc
from tests.support.fakepeer import FakeNode
from tests.support.procs import wait_for


@pytest.fixture
def master() -> Iterator[MasterThread]:
    with MasterThread() as m:
        yield m


def _post(port: int, body: bytes, path: str = "/", version: str = "HTTP/1.1") -> bytes:
    with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
        s.sendall(f"POST {path} {version}\r\nContent-Length: {len(body)}\r\n\r\n".encode() + body)
        chunks = []
        while data := s.recv(65536):
            chunks.append(data)
            if version == "HTTP/1.1" and b"</methodResponse>" in b"".join(chunks):
                break
        return b"".join(chunks)


def test_keep_alive_many_calls_on_one_connection(master: MasterThread) -> None:
    port = master.master.port  # type: ignore[union-attr]
    conn = http.client.HTTPConnection("127.0.0.1", port, timeout=5)
    for i in range(20):
        body = xmlrpc.client.dumps(("/c", f"/p{i}", i), "setParam").encode()
        conn.request("POST", "/RPC2", body, {"Content-Type": "text/xml"})
        response = conn.getresponse()
        assert response.status == 200
        assert xmlrpc.client.loads(response.read())[0][0] == [1, f"parameter /p{i} set", 0]
    conn.close()


def test_any_path_and_http10(master: MasterThread) -> None:
    port = master.master.port  # type: ignore[union-attr]
    body = xmlrpc.client.dumps(("/c",), "getUri").encode()
    reply = _post(port, body, path="/some/odd/path", version="HTTP/1.0")
    assert reply.startswith(b"HTTP/1.1 200 OK") and b"Connection: close" in reply
    assert master.uri.encode() in reply


def test_hostile_clients_get_errors_and_the_master_keeps_serving(master: MasterThread) -> None:
    port = master.master.port  # type: ignore[union-attr]
    reply = _post(port, b"<not xml")  # a fault, as rosmaster answers (see test_hostile_xmlrpc)
    assert reply.startswith(b"HTTP/1.1 200") and b"<fault>" in reply
    huge = f"POST / HTTP/1.1\r\nContent-Length: {1 << 30}\r\n\r\n".encode()
    with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
        s.sendall(huge)
        assert s.recv(100).startswith(b"HTTP/1.1 413")
    # Half-open clients: one sends half a request, one sends nothing; others still get served.
    stalled = [socket.create_connection(("127.0.0.1", port)) for _ in range(2)]
    stalled[0].sendall(b"POST / HTTP/1.1\r\nContent-Length: 100\r\n\r\n<?xml")
    proxy = xmlrpc.client.ServerProxy(master.uri)
    assert proxy.getParam("/c", "/nope") == [-1, "Parameter [/nope] is not set", 0]
    assert proxy.getPid(1)[:2] == [-1, "caller_id must be a string"]
    assert proxy.registerPublisher("/c", "/t")[:2] == [-1, "Error: bad call arity"]
    for s in stalled:
        s.close()
    assert proxy.getUri("/c")[0] == 1


def test_concurrent_clients(master: MasterThread) -> None:
    errors: list[BaseException] = []

    def client(n: int) -> None:
        try:
            proxy = xmlrpc.client.ServerProxy(master.uri)
            for i in range(50):
                node = f"http://127.0.0.1:{20000 + n}/"
                assert proxy.registerPublisher(f"/n{n}", f"/t{i}", "a/B", node)[0] == 1
        except BaseException as err:  # noqa: BLE001
            errors.append(err)

    threads = [threading.Thread(target=client, args=(n,)) for n in range(6)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert not errors
    pubs = xmlrpc.client.ServerProxy(master.uri).getSystemState("/c")[2][0]
    assert len(pubs) == 50 and all(len(nodes) == 6 for _, nodes in pubs)


def recording_node() -> FakeNode:
    """A slave API that records what the master sends a node."""
    return FakeNode(
        dict.fromkeys(("publisherUpdate", "paramUpdate", "shutdown"), lambda *_: [1, "", 0])
    )


def test_notifications_reach_nodes(master: MasterThread) -> None:
    sub, old = recording_node(), recording_node()
    try:
        proxy = xmlrpc.client.ServerProxy(master.uri)
        proxy.registerSubscriber("/listener", "/chatter", "std_msgs/String", sub.uri)
        proxy.registerPublisher("/talker", "/chatter", "std_msgs/String", "http://127.0.0.1:1/")
        proxy.subscribeParam("/listener", sub.uri, "/gain")
        proxy.setParam("/other", "/gain", 2.5)
        proxy.registerPublisher("/old", "/x", "a/B", old.uri)
        proxy.registerPublisher("/old", "/y", "a/B", "http://127.0.0.1:2/")
        wait_for(lambda: len(sub.calls) >= 2 and old.calls, 5, "notifications")
        assert ("publisherUpdate", ("/master", "/chatter", ["http://127.0.0.1:1/"])) in sub.calls
        assert ("paramUpdate", ("/master", "/gain/", 2.5)) in sub.calls
        assert old.calls == [
            ("shutdown", ("/master", "[/old] Reason: new node registered with same name"))
        ]
    finally:
        sub.close()
        old.close()


def test_shutdown_call_stops_the_master() -> None:
    m = MasterThread().start()
    proxy = xmlrpc.client.ServerProxy(m.uri)
    assert proxy.shutdown("/c", "done") == [1, "shutdown", 0]
    assert m._thread is not None
    m._thread.join(5)
    assert not m._thread.is_alive()
    time.sleep(0.1)
    with pytest.raises(OSError):
        proxy.getPid("/c")


def test_cached_answers_follow_the_caller_and_the_checks(master: MasterThread) -> None:
    # the defects: the read-only answer cache keyed on the raw arguments, before any check
    proxy = xmlrpc.client.ServerProxy(master.uri)
    for topic in ("/a/sub/x", "/b/sub/y"):
        assert proxy.registerPublisher("/p", topic, "std_msgs/String", "http://h:1/")[0] == 1
    assert proxy.getPublishedTopics("/a/n", "sub") == [
        1, "current topics", [["/a/sub/x", "std_msgs/String"]]
    ]  # fmt: skip
    assert proxy.getPublishedTopics("/b/n", "sub") == [
        1, "current topics", [["/b/sub/y", "std_msgs/String"]]
    ]  # fmt: skip
    assert proxy.getSystemState("/c")[0] == 1  # now cached
    assert proxy.getSystemState(5) == [-1, "caller_id must be a string", [[], [], []]]
    assert proxy.getPublishedTopics("/c", ["not", "hashable"]) == [
        -1, "ERROR: parameter [subgraph] must be a string", 0
    ]  # fmt: skip
    assert proxy.getPublishedTopics("/c", {"a": 1})[0] == -1


def test_a_huge_multicall_does_not_stall_other_clients(master: MasterThread) -> None:
    # the defect: a multicall of 100,000 calls held the event loop; every other client's
    # getSystemState waited up to 4.5 s (rosmaster, threaded: under 0.2 s)
    calls = [{"methodName": "getPid", "params": ["/big"]}] * 100_000
    answer: list[Any] = []
    big = threading.Thread(
        target=lambda: answer.append(xmlrpc.client.ServerProxy(master.uri).system.multicall(calls))
    )
    proxy = xmlrpc.client.ServerProxy(master.uri)
    started = time.monotonic()
    big.start()
    waits = []
    while big.is_alive():
        began = time.monotonic()
        assert proxy.getSystemState("/small")[0] == 1
        waits.append(time.monotonic() - began)
    big.join()
    took = time.monotonic() - started
    assert len(answer[0]) == 100_000 and answer[0][-1][0][0] == 1
    # relative to the big call, not in seconds: master, both clients and pytest share one
    # GIL, and a loaded machine stretches everything (1.5 s failed there once); with the
    # defect the small call waits for nearly the whole big one
    assert len(waits) > 5 and max(waits) < took / 3, (
        f"{len(waits)} calls, worst {max(waits):.2f} s of {took:.2f} s"
    )


def test_a_bad_multicall_entry_is_a_fault(master: MasterThread, capsys: Any) -> None:
    # the defect: params that were not a list printed a traceback on the master
    results = xmlrpc.client.ServerProxy(master.uri).system.multicall(
        [{"methodName": "getPid", "params": 5}, {"methodName": "getPid", "params": ["/c"]}]
    )
    assert results[0] == {"faultCode": 1, "faultString": "multicall params must be an array"}
    assert results[1][0][0] == 1
    assert "Traceback" not in capsys.readouterr().err


def test_large_bodies_share_one_budget(master: MasterThread) -> None:
    # the defect: six connections promising 63 MiB each and sending slowly held 416 MB
    port = master.master.port  # type: ignore[union-attr]
    promised = f"POST / HTTP/1.1\r\nContent-Length: {60 << 20}\r\n\r\n".encode() + b"x" * 1000
    socks = [socket.create_connection(("127.0.0.1", port), timeout=5) for _ in range(3)]
    try:
        for sock in socks:
            sock.sendall(promised)
            time.sleep(0.2)
        refused = socks[2].recv(200)
        assert refused.startswith(b"HTTP/1.1 503 Service Unavailable"), refused
        assert xmlrpc.client.ServerProxy(master.uri).getPid("/c")[0] == 1  # small calls go on
    finally:
        for sock in socks:
            sock.close()


def test_a_trickling_request_meets_one_deadline(
    master: MasterThread, monkeypatch: pytest.MonkeyPatch
) -> None:
    # the defect: the request timeout restarted with every byte, so a byte a second was
    # never closed
    monkeypatch.setattr(graph_xmlrpc, "REQUEST_TIMEOUT", 0.5)
    port = master.master.port  # type: ignore[union-attr]
    with socket.create_connection(("127.0.0.1", port), timeout=5) as sock:
        began = time.monotonic()
        try:
            for byte in b"POST / HTTP/1.1\r\nContent-Length: 100\r\n\r\n":
                sock.send(bytes([byte]))
                time.sleep(0.1)
        except OSError:
            pass  # closed under us, as it should be
        closed_after = time.monotonic() - began
    assert closed_after < 2.5


def _deep_set_body(depth: int) -> bytes:
    """A setParam of /deep to a struct nested ``depth`` levels, as raw XML (a client's
    marshaller would recurse too deep to write it)."""
    opening = "<value><struct><member><name>a</name>" * depth
    closing = "</member></struct></value>" * depth
    return (
        "<?xml version='1.0'?><methodCall><methodName>setParam</methodName><params>"
        "<param><value><string>/c</string></value></param>"
        "<param><value><string>/deep</string></value></param>"
        f"<param>{opening}<value><int>1</int></value>{closing}</param></params></methodCall>"
    ).encode()


def test_absurdly_deep_parameters_are_refused(master: MasterThread, capsys: Any) -> None:
    # the defect: a parameter nested 100k deep was stored, and every getParam / after it
    # printed a RecursionError traceback of about 110 KB on the master
    port = master.master.port  # type: ignore[union-attr]
    answer = xmlrpc.client.loads(_post(port, _deep_set_body(5000)).split(b"\r\n\r\n", 1)[1])
    assert answer[0][0] == [
        -1, "ERROR: parameter [/deep] would nest deeper than 100 levels", 0
    ]  # fmt: skip
    proxy = xmlrpc.client.ServerProxy(master.uri)
    long_key = "/k" * 5000
    assert proxy.setParam("/c", long_key, 1)[0] == -1
    assert proxy.setParam("/c", "/ok/" + "/".join("n" * 10), {"x": [[1]]})[0] == 1
    for _ in range(3):
        assert proxy.getParam("/c", "/")[0] == 1
    assert "Traceback" not in capsys.readouterr().err


def test_small_requests_allocate_no_big_read_buffers(master: MasterThread) -> None:
    import tracemalloc

    port = master.master.port  # type: ignore[union-attr]
    body = xmlrpc.client.dumps(("/c",), "getPid").encode()
    request = f"POST / HTTP/1.1\r\nContent-Length: {len(body)}\r\n\r\n".encode() + body
    with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
        s.sendall(request)
        s.recv(65536)
        tracemalloc.start()
        try:
            for _ in range(10):
                s.sendall(request)
                assert b"</methodResponse>" in s.recv(65536)
            _, peak = tracemalloc.get_traced_memory()
        finally:
            tracemalloc.stop()
    # asyncio's plain recv allocated 256 KiB per read (mmap, mremap and munmap per request).
    assert peak < 128 * 1024


def test_a_node_too_slow_for_its_publisher_update_gets_it_again(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """A subscriber too busy to answer publisherUpdate in time got it once, and never
    connected to the publisher (a rospy listener beside two CPU hogs heard nothing)."""
    monkeypatch.setattr(graph_xmlrpc, "CALL_TIMEOUT", 0.3)
    busy = [True]

    def update(caller: str, topic: str, uris: list[str]) -> list[Any]:
        if busy[0]:
            busy[0] = False
            time.sleep(0.6)  # past the first limit, not the second
        return [1, "", 0]

    with MasterThread() as master, FakeNode({"publisherUpdate": update}) as node:
        with xmlrpc.client.ServerProxy(master.uri) as proxy:
            proxy.registerSubscriber("/slow_sub", "/t", "std_msgs/String", node.uri)
            proxy.registerPublisher("/pub", "/t", "std_msgs/String", "http://127.0.0.1:1/")
        wait_for(lambda: len(node.calls) >= 2, 30, "publisherUpdate sent again")
    assert [c[1][1:] for c in node.calls] == [("/t", ["http://127.0.0.1:1/"])] * 2
