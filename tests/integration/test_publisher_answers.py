"""What a publisher's slave API answers to requestTopic: a refusal, or no port to connect to.

A node on its way out refuses the topics it has already dropped (roscpp does, for each of
its topics): that was reported at once, one line per topic (34-74 lines when a roscpp node
of 1,000 topics went away). An answer without a port number crashed the subscriber's task.
"""

from __future__ import annotations

import xmlrpc.client
from collections.abc import Iterator
from typing import Any

import pytest

from tests.support.fakepeer import FakeNode
from tests.support.procs import Proc, start_cli, wait_for


class FakeSlave(FakeNode):
    """A registered publisher of /t whose requestTopic answers ``answer``."""

    def __init__(self, master_uri: str, answer: list[Any]) -> None:
        self.master = xmlrpc.client.ServerProxy(master_uri)
        super().__init__({"requestTopic": lambda *_: answer})
        self.master.registerPublisher("/leaving", "/t", "std_msgs/String", self.uri)

    def leave(self) -> None:
        """Unregister, as a node shutting down does."""
        self.master.unregisterPublisher("/leaving", "/t", self.uri)


@pytest.fixture
def echo(cli_env: dict[str, str]) -> Iterator[Proc]:
    proc = start_cli("topic", "echo", "/t", "--timeout", "4", env=cli_env)
    yield proc
    proc.stop()


def test_a_refusal_from_a_node_on_its_way_out_is_not_reported(
    rostools_master: str, echo: Proc
) -> None:
    slave = FakeSlave(rostools_master, [-1, "/t is not a published topic", 0])
    try:
        wait_for(lambda: slave.asked("requestTopic"), 15, "echo to ask")  # and be refused
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
