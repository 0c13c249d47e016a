"""A publisher of many topics that answers ``requestTopic`` slowly, one call at a time.

A busy roscpp node answers its slave API calls one after another. A recorder of all its
topics asked for every topic at once: those at the back of the queue timed out and were asked
again, so the node spent its time on answers nobody waited for (on a loaded machine, a
thousand-topic recording followed a tenth of its topics). Now at most ``PEER_CALLS`` calls
are in flight to one node, and each gets the whole limit.
"""

from __future__ import annotations

import socket
import struct
import threading
import time
import xmlrpc.client
from collections.abc import Iterator
from pathlib import Path

import pytest

from rostools.master.server import MasterThread
from rostools.node import subscriber
from rostools.node.subscriber import PEER_CALLS
from tests.support.fakepeer import FakeNode, FakePublisher, first_frames, frame, valid_header
from tests.support.procs import start_cli, wait_for

TOPICS = 20
#: Each answer takes this long (s): 20 in a row are 8 s, past the 5 s limit of a call.
ANSWER = 0.4


@pytest.fixture
def tcpros() -> Iterator[tuple[int, list[socket.socket]]]:
    """A TCPROS port that takes connections and says nothing: its port, and what it took."""
    server = socket.create_server(("127.0.0.1", 0), backlog=TOPICS * 2)
    taken: list[socket.socket] = []

    def accept() -> None:
        while True:
            try:
                taken.append(server.accept()[0])
            except OSError:
                return

    threading.Thread(target=accept, daemon=True).start()
    yield server.getsockname()[1], taken
    server.close()
    for conn in taken:
        conn.close()


def test_a_slow_publisher_of_many_topics_is_asked_once_per_topic(
    rostools_master: str,
    cli_env: dict[str, str],
    tcpros: tuple[int, list[socket.socket]],
    tmp_path: Path,
) -> None:
    port, taken = tcpros

    def request_topic(caller: str, topic: str, protocols: object) -> object:
        time.sleep(ANSWER)  # one at a time: the server has one thread, as roscpp's
        return [1, "", ["TCPROS", "127.0.0.1", port]]

    with FakeNode({"requestTopic": request_topic}) as fake:
        with xmlrpc.client.ServerProxy(rostools_master) as master:
            for i in range(TOPICS):
                code, msg, _ = master.registerPublisher(
                    "/busy", f"/busy_{i}", "std_msgs/String", fake.uri
                )
                assert code == 1, msg
        record = start_cli("bag", "record", "-a", "-O", str(tmp_path / "r.bag"), env=cli_env)
        try:
            wait_for(lambda: len(taken) >= TOPICS, 60, f"{TOPICS} connections")
        finally:
            record.stop()
        asked = fake.asked("requestTopic")
    # each topic was asked for once: no call timed out behind the others
    assert asked == TOPICS, f"{asked} requestTopic calls for {TOPICS} topics"
    assert PEER_CALLS * ANSWER < 5.0 < TOPICS * ANSWER  # the shape that made calls time out


def test_a_publisher_slow_to_shake_hands_is_given_longer_each_time(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # A busy publisher that sent its header after HANDSHAKE_TIMEOUT was dropped, asked again
    # from scratch (more work for it) and dropped again, for as long as it stayed busy.
    monkeypatch.setattr(subscriber, "HANDSHAKE_TIMEOUT", 0.4)

    def busy(sock: socket.socket) -> None:
        time.sleep(1.0)  # longer than the usual limit, shorter than four times it
        sock.sendall(valid_header("/late") + frame(struct.pack("<I", 2) + b"hi"))

    with MasterThread() as master, FakePublisher(master.uri, "/late", busy) as fake:
        got = first_frames(master.uri, "/late", "/patient", within=20)
        assert got == [struct.pack("<I", 2) + b"hi"]
        assert len(fake.connections) >= 2  # it was dropped once, at least, then waited for
