"""What a publisher's slave API answers to requestTopic: a refusal, or no port to connect to.

A node on its way out refuses the topics it has already dropped (roscpp does, for each of
its topics): that was reported at once, one line per topic (34-74 lines when a roscpp node
of 1,000 topics went away). An answer without a port number crashed the subscriber's task.
"""

from __future__ import annotations

import sys
import threading
import xmlrpc.client
from collections.abc import Iterator
from typing import Any
from xmlrpc.server import SimpleXMLRPCServer

import pytest

from tests.support.procs import Proc


class FakeSlave:
    """A registered publisher of /t whose requestTopic answers ``answer``."""

    def __init__(self, master_uri: str, answer: list[Any]) -> None:
        self.master = xmlrpc.client.ServerProxy(master_uri)
        self.rpc = SimpleXMLRPCServer(("127.0.0.1", 0), logRequests=False, allow_none=True)
        self.asked = threading.Event()

        def request_topic(*_: Any) -> list[Any]:
            self.asked.set()
            return answer

        self.rpc.register_function(request_topic, "requestTopic")
        self.uri = f"http://127.0.0.1:{self.rpc.server_address[1]}/"
        threading.Thread(target=self.rpc.serve_forever, daemon=True).start()
        self.master.registerPublisher("/leaving", "/t", "std_msgs/String", self.uri)

    def leave(self) -> None:
        self.master.unregisterPublisher("/leaving", "/t", self.uri)

    def close(self) -> None:
        self.rpc.shutdown()
        self.rpc.server_close()


@pytest.fixture
def echo(cli_env: dict[str, str]) -> Iterator[Proc]:
    proc = Proc([sys.executable, "-m", "rostools", "topic", "echo", "/t", "--timeout", "4"],
                env=cli_env)  # fmt: skip
    yield proc
    proc.stop()


def test_a_refusal_from_a_node_on_its_way_out_is_not_reported(
    rostools_master: str, echo: Proc
) -> None:
    slave = FakeSlave(rostools_master, [-1, "/t is not a published topic", 0])
    try:
        assert slave.asked.wait(15)  # echo subscribed and was refused
        slave.leave()  # then the node goes, as a node shutting down does
        assert echo.popen.wait(20) == 5  # nothing arrived within --timeout
        _, err = echo.output()
    finally:
        slave.close()
    assert "refused" not in err, err


def test_a_refusal_that_lasts_is_reported(rostools_master: str, echo: Proc) -> None:
    slave = FakeSlave(rostools_master, [-1, "/t is not a published topic", 0])
    try:
        assert echo.popen.wait(20) == 5
        _, err = echo.output()
    finally:
        slave.close()
    assert "/leaving at http://127.0.0.1:" in err
    assert "it refused the topic: /t is not a published topic" in err


def test_an_answer_without_a_port_is_one_line(rostools_master: str, echo: Proc) -> None:
    slave = FakeSlave(rostools_master, [1, "ready", ["TCPROS", "127.0.0.1", "not a port"]])
    try:
        assert echo.popen.wait(20) == 5
        _, err = echo.output()
    finally:
        slave.close()
    assert "it gave no port to connect to: ['TCPROS', '127.0.0.1', 'not a port']" in err, err
    assert "Traceback" not in err and "exception" not in err.lower(), err
