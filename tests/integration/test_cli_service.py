"""``rostools service`` and the service transport, rostools on both ends."""

from __future__ import annotations

import asyncio
import json
import socket
import sys
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.support.env import run_cli
from tests.support.procs import Proc

RT_SERVICES = Path(__file__).parent.parent / "support" / "rt_nodes" / "rt_services.py"


@pytest.fixture
def services(rostools_master: str, cli_env: dict[str, str]) -> Iterator[Proc]:
    proc = Proc([sys.executable, str(RT_SERVICES)], env=cli_env)
    try:
        proc.expect("ready", 20)
        yield proc
    finally:
        proc.stop()


def test_every_service_command(services: Proc, cli_env: dict[str, str]) -> None:
    def cli(*args: str) -> str:
        out = run_cli("service", *args, env=cli_env)
        assert out.returncode == 0, out.stderr
        return out.stdout

    assert "/add_two_ints rt_services\n" not in cli("list", "-n")
    assert "/add_two_ints /rt_services\n" in cli("list", "-n")
    assert cli("list", "/rosout").split() == ["/rosout/get_loggers", "/rosout/set_logger_level"]
    assert cli("type", "/add_two_ints") == "rospy_tutorials/AddTwoInts\n"
    assert cli("args", "/add_two_ints") == "a b\n"
    assert cli("uri", "/add_two_ints").startswith("rosrpc://127.0.0.1:")
    assert cli("node", "/add_two_ints") == "/rt_services\n"  # rosservice node
    info = cli("info", "/set_bool")
    assert info.startswith("Node: /rt_services\nURI: rosrpc://") and info.endswith(
        "Type: std_srvs/SetBool\nArgs: data\n"
    )
    assert cli("find", "std_srvs/Trigger") == "/trigger\n"
    assert cli("call", "/add_two_ints", "{a: 1, b: 2}") == "sum: 3\n"
    assert cli("call", "/add_two_ints", "40", "2", "-v") == "a: 40\nb: 2\n---\nsum: 42\n"
    assert json.loads(cli("call", "/set_bool", "true", "-F", "json")) == {
        "success": True,
        "message": "set True",
    }
    piped = run_cli(
        "service", "call", "/add_two_ints", env=cli_env, input="{a: 1, b: 1}\n---\n{a: 2, b: 2}\n"
    )
    assert piped.stdout == "sum: 2\nsum: 4\n"
    assert cli("call", "/trigger") == 'success: True\nmessage: "triggered 1"\n'
    assert cli("call", "/trigger", "--nostr") == 'success: True\nmessage: "<string length: 11>"\n'


@pytest.mark.parametrize(
    ("args", "code", "text"),
    [
        (
            ["call", "/add_two_ints", "{a: -5, b: 1}"],
            1,
            "failed: service cannot process request: refusing",
        ),
        (["call", "/add_two_ints", "{a: 1, c: 2}"], 2, "(hint: /add_two_ints takes: a b)"),
        (["call", "/add_two_ints", "1"], 2, "takes 2 values in field order, got 1"),
        (["call", "/nope"], 3, "unknown service /nope"),
        (["type", "/nope"], 3, "unknown service /nope"),
        (["info", "/nope"], 3, "unknown service /nope"),
        (["call", "--wait", "--timeout", "1", "/later"], 5, "did not appear within 1 s"),
    ],
)
def test_errors(
    services: Proc, cli_env: dict[str, str], args: list[str], code: int, text: str
) -> None:
    out = run_cli("service", *args, env=cli_env)
    assert out.returncode == code, out.stderr
    assert text in out.stderr and len(out.stderr.strip().splitlines()) == 1


@pytest.mark.parametrize(
    ("behaviour", "code", "text"),
    [
        ("dies", 1, "closed the connection without responding"),
        ("garbage", 1, "garbage from service /bad"),
        ("silent", 5, "did not respond within 1 s"),
    ],
)
def test_broken_servers_never_hang_the_client(
    rostools_master: str, cli_env: dict[str, str], behaviour: str, code: int, text: str
) -> None:
    import xmlrpc.client

    listener, _ = _fake_server(behaviour)
    port = listener.getsockname()[1]
    proxy = xmlrpc.client.ServerProxy(rostools_master)
    proxy.registerService("/bad", "/bad", f"rosrpc://127.0.0.1:{port}", "http://127.0.0.1:1/")
    out = run_cli("service", "call", "/bad", "--timeout", "1", env=cli_env)
    assert out.returncode == code, out.stderr
    assert text in out.stderr
    listener.close()


def _fake_server(behaviour: str) -> tuple[socket.socket, threading.Thread]:
    """A service server that misbehaves on the call: dies, answers garbage, or stays silent."""
    from rostools.wire.tcpros import service_reply_header

    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen()
    reply = service_reply_header(
        "/bad", "/bad", "937c9679a518e3a18d831e57125ea522", "std_srvs/Trigger"
    )

    def serve() -> None:
        probe, _ = listener.accept()  # the type probe
        probe.recv(65536)
        probe.sendall(reply)
        probe.close()
        conn, _ = listener.accept()  # the call
        conn.recv(65536)
        conn.sendall(reply)
        if behaviour == "garbage":
            conn.sendall(b"\x07garbage!")
        elif behaviour == "silent":
            threading.Event().wait(3)
        conn.close()

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    return listener, thread


def test_persistent_async_client(services: Proc, rostools_master: str) -> None:
    from rostools.msgs.codec import Codec
    from rostools.msgs.store import BuiltinSource, TypeStore
    from rostools.msgs.topictype import ServiceType
    from rostools.node.node import LiveNode
    from rostools.node.service import ServiceClient

    store = TypeStore([BuiltinSource()])
    codec = Codec.of(store)

    async def main() -> list[int]:
        node = await LiveNode("client", rostools_master, anonymous_name=True).start()
        try:
            client = ServiceClient(
                node,
                "/add_two_ints",
                ServiceType.of(store, "rospy_tutorials/AddTwoInts"),
                persistent=True,
            )
            sums = []
            for i in range(20):
                request = codec.message_class("rospy_tutorials/AddTwoIntsRequest")(i, i).serialize()
                sums.append(
                    codec.decode(
                        "rospy_tutorials/AddTwoIntsResponse", await client.call(request)
                    ).sum
                )
            first = client._proto
            assert first is not None  # one connection kept for every call
            client.close()
            header = await ServiceClient(node, "/trigger").probe()
            assert header["type"] == "std_srvs/Trigger"
            return sums
        finally:
            await node.close()

    assert asyncio.run(main()) == [2 * i for i in range(20)]
