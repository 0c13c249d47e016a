"""Peers that are not real nodes, so tests can play a hostile, broken or watched one.

``FakeNode`` is a node's slave API that answers what the test says and records every call;
``FakePublisher`` registers, answers ``requestTopic``, and then sends each subscriber whatever
the test says.
"""

from __future__ import annotations

import asyncio
import socket
import struct
import threading
import xmlrpc.client
from collections.abc import Callable, Mapping
from types import TracebackType
from typing import Any
from xmlrpc.server import SimpleXMLRPCRequestHandler, SimpleXMLRPCServer

from rostools.node.node import LiveNode
from rostools.wire.tcpros import publisher_header

STRING_MD5 = "992ce8a1687cec8c8bd883ec73ca41d1"


def frame(payload: bytes) -> bytes:
    """``payload`` with its TCPROS length prefix."""
    return struct.pack("<I", len(payload)) + payload


def valid_header(topic: str, name: str = "/fake") -> bytes:
    """A std_msgs/String publisher's reply header, length prefix included."""
    return publisher_header(name, topic, STRING_MD5, "std_msgs/String", "string data\n", False)


HEADER_MD5 = "2176decaecbce78abc3b96ef049fabed"


def header_type_header(topic: str, name: str = "/fake") -> bytes:
    """A std_msgs/Header publisher's reply header, length prefix included."""
    definition = "uint32 seq\ntime stamp\nstring frame_id\n"
    return publisher_header(name, topic, HEADER_MD5, "std_msgs/Header", definition, False)


def first_frames(master_uri: str, topic: str, name: str, within: float = 10.0) -> list[bytes]:
    """The frames of the first read a new node ``name`` gets on ``topic`` within ``within``
    seconds (none: an empty list); the node is closed after."""

    async def main() -> list[bytes]:
        node = await LiveNode(name, master_uri).start()
        got: list[bytes] = []
        try:
            await node.subscribe(topic, lambda frames, conn, t: got.extend(map(bytes, frames)))
            for _ in range(int(within / 0.05)):
                if got:
                    break
                await asyncio.sleep(0.05)
        finally:
            await node.close()
        return got

    return asyncio.run(main())


class _QuietHandler(SimpleXMLRPCRequestHandler):
    """No log line on stderr for a client that hangs up or sends junk (tests do both)."""

    def log_message(self, format: str, *args: Any) -> None:
        pass


class FakeNode:
    """A slave API on loopback, served from a thread until ``close``; records every call.

    ``answers`` maps a method to a function of the call's parameters that returns the answer;
    any other method is a fault, as it is to ``SimpleXMLRPCServer``.
    """

    def __init__(self, answers: Mapping[str, Callable[..., Any]]) -> None:
        self.answers = dict(answers)
        #: (method, parameters) of each call, in the order they came.
        self.calls: list[tuple[str, tuple[Any, ...]]] = []
        self.server = SimpleXMLRPCServer(
            ("127.0.0.1", 0), requestHandler=_QuietHandler, logRequests=False, allow_none=True
        )
        self.server.register_instance(self)  # every call goes through _dispatch
        self.uri = f"http://127.0.0.1:{self.server.server_address[1]}/"
        threading.Thread(target=self.server.serve_forever, daemon=True).start()

    def _dispatch(self, method: str, params: tuple[Any, ...]) -> Any:
        answer = self.answers.get(method)
        if answer is None:
            raise xmlrpc.client.Fault(1, f'method "{method}" is not supported')
        self.calls.append((method, params))
        return answer(*params)

    def asked(self, method: str) -> int:
        """How many times ``method`` has been called."""
        return sum(1 for name, _ in self.calls if name == method)

    def close(self) -> None:
        """Stop serving and free the port."""
        self.server.shutdown()
        self.server.server_close()

    def __enter__(self) -> FakeNode:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()


class FakePublisher:
    """``with FakePublisher(master, "/t", send) as fake:``; ``send(sock)`` runs per subscriber.

    ``send`` gets the socket after the subscriber's header has been read; when it returns,
    the connection stays open until the fake stops.
    """

    def __init__(
        self,
        master_uri: str,
        topic: str,
        send: Callable[[socket.socket], None],
        name: str = "/fake",
        msg_type: str = "std_msgs/String",
    ) -> None:
        self.master_uri, self.topic, self.send, self.name = master_uri, topic, send, name
        self.msg_type = msg_type
        self.tcp = socket.create_server(("127.0.0.1", 0))
        port = self.tcp.getsockname()[1]
        answer = [1, "", ["TCPROS", "127.0.0.1", port]]
        self.rpc = FakeNode({"requestTopic": lambda caller, topic, protocols: answer})
        self.uri = self.rpc.uri
        self.connections: list[socket.socket] = []
        self.stopped = threading.Event()

    def __enter__(self) -> FakePublisher:
        threading.Thread(target=self._accept, daemon=True).start()
        with xmlrpc.client.ServerProxy(self.master_uri) as master:
            code, message, _ = master.registerPublisher(
                self.name, self.topic, self.msg_type, self.uri
            )
        assert code == 1, message
        return self

    def _accept(self) -> None:
        while not self.stopped.is_set():
            try:
                conn, _ = self.tcp.accept()
            except OSError:
                return
            self.connections.append(conn)
            threading.Thread(target=self._serve, args=(conn,), daemon=True).start()

    def _serve(self, conn: socket.socket) -> None:
        try:
            (length,) = struct.unpack("<I", conn.recv(4, socket.MSG_WAITALL))
            conn.recv(length, socket.MSG_WAITALL)
            self.send(conn)
        except OSError:
            pass

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.stopped.set()
        self.rpc.close()
        self.tcp.close()
        for conn in self.connections:
            conn.close()
