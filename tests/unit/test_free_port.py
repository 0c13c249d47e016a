"""The tests' free ports are never ones the kernel hands out to others."""

from __future__ import annotations

import socket

from tests.support.procs import ephemeral_ports, free_port


def test_a_free_port_is_below_the_ephemeral_range_and_bindable() -> None:
    low, _ = ephemeral_ports()
    for _ in range(50):
        port = free_port()
        assert 1024 <= port < low  # roscore's roslaunch server once took the master's port
        with socket.socket() as s:
            s.bind(("127.0.0.1", port))
