"""A publisher that is not one: it registers, answers ``requestTopic``, and then sends each
subscriber whatever the test says, so tests can play a hostile or broken peer.
"""

from __future__ import annotations

import socket
import struct
import threading
import xmlrpc.client
from collections.abc import Callable
from types import TracebackType
from xmlrpc.server import SimpleXMLRPCServer

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
        self.rpc = SimpleXMLRPCServer(("127.0.0.1", 0), logRequests=False, allow_none=True)
        port = self.tcp.getsockname()[1]
        self.rpc.register_function(
            lambda caller, topic, protocols: [1, "", ["TCPROS", "127.0.0.1", port]], "requestTopic"
        )
        self.uri = f"http://127.0.0.1:{self.rpc.server_address[1]}/"
        self.connections: list[socket.socket] = []
        self.stopped = threading.Event()

    def __enter__(self) -> FakePublisher:
        threading.Thread(target=self.rpc.serve_forever, daemon=True).start()
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
        self.rpc.shutdown()
        self.rpc.server_close()
        self.tcp.close()
        for conn in self.connections:
            conn.close()
