"""``node kill``'s shutdown call: a node that closes the connection while it answers was told.

rosnode counts a node that drops the connection mid-answer as killed; a refused connection
is a failure. The real client code raises here (a unit test used to build the exception chain
itself, so the code that raises never ran).
"""

from __future__ import annotations

import socket
import struct
import threading
from collections.abc import Iterator

import pytest

from rostools.errors import UnreachableError
from rostools.rosgraph.nodeapi import NodeApi
from tests.support.procs import free_port


@pytest.fixture(params=["closes", "resets"])
def dropping_node(request: pytest.FixtureRequest) -> Iterator[str]:
    """A slave API that reads a request and drops the connection without an answer."""
    server = socket.create_server(("127.0.0.1", 0))
    port = server.getsockname()[1]

    def serve() -> None:
        conn, _ = server.accept()
        conn.recv(65536)
        if request.param == "resets":  # RST, not FIN
            conn.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
        conn.close()

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{port}/"
    finally:
        server.close()
        thread.join(5)


def test_a_node_that_drops_the_answer_was_shut_down(dropping_node: str) -> None:
    NodeApi("/n", dropping_node, "/rosnode", 3.0).shutdown()  # no error: rosnode's success


def test_a_refused_connection_is_a_failure() -> None:
    nobody = f"http://127.0.0.1:{free_port()}/"
    with pytest.raises(UnreachableError):
        NodeApi("/n", nobody, "/rosnode", 3.0).shutdown()
