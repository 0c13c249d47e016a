"""``rostools __complete``'s deadline: it bounds the graph queries, counted from the first one.

Before, it counted from the process's start: on a busy machine the interpreter's start-up
spent it all, and a TAB completed nothing, not even a command's name.
"""

from __future__ import annotations

import contextlib
import os
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from xmlrpc.server import SimpleXMLRPCServer

import pytest

from rostools.cli.completer import main
from tests.support.procs import silent_port


def complete(capsys: pytest.CaptureFixture[str], *words: str) -> list[str]:
    """The values ``rostools __complete bash`` prints for the last of ``words``."""
    assert main(["bash", str(len(words)), "rostools", *words]) == 0
    return [line.split("\t")[0] for line in capsys.readouterr().out.splitlines()]


@pytest.fixture
def slow_master() -> Iterator[str]:
    """A master in a thread that takes 0.2 s to say that /chatter has a publisher."""

    def get_system_state(caller_id: str) -> list[object]:
        time.sleep(0.2)  # a slow answer, well within the budget the test gives
        return [1, "", [[["/chatter", ["/talker"]]], [], []]]

    server = SimpleXMLRPCServer(("127.0.0.1", 0), logRequests=False)
    server.register_function(get_system_state, "getSystemState")
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}"
    finally:
        server.shutdown()
        server.server_close()
        thread.join()


#: ``rostools __complete`` whose interpreter takes 1.2 s to start, as on a busy machine.
SLOW_START = """
import sys, time
time.sleep(1.2)
from rostools.cli.completer import main
sys.exit(main(sys.argv[1:]))
"""


def test_the_deadline_counts_the_query_not_the_start_up(slow_master: str) -> None:
    # before: the start-up alone spent the second the master's 0.2 s answer had
    env = dict(os.environ, ROS_MASTER_URI=slow_master, ROSTOOLS_COMPLETE_DEADLINE="1")
    argv = [sys.executable, "-c", SLOW_START, "bash", "3", "rostools", "topic", "echo", "/ch"]
    done = subprocess.run(argv, env=env, capture_output=True, text=True, timeout=60)
    assert (done.returncode, done.stdout, done.stderr) == (0, "/chatter\n", "")


def test_offline_words_have_no_deadline(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    # a deadline of nothing at all: before, a type (whose listing takes a while) was cut off
    monkeypatch.setenv("ROSTOOLS_COMPLETE_DEADLINE", "0")
    monkeypatch.setenv("ROS_MASTER_URI", "http://127.0.0.1:9")
    assert complete(capsys, "topic", "ec") == ["echo"]
    assert complete(capsys, "--form") == ["--format"]
    assert complete(capsys, "topic", "echo", "--format=ya") == ["yaml"]
    assert complete(capsys, "msg", "show", "geometry_msgs/PointSt") == [
        "geometry_msgs/PointStamped"
    ]
    assert complete(capsys, "bag", "info", "") == [":files bag mcap active"]


def test_a_silent_master_gives_what_can_be_had_without_it(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    with silent_port() as port:
        monkeypatch.setenv("ROS_MASTER_URI", f"http://127.0.0.1:{port}")
        assert complete(capsys, "topic", "echo", "/") == []
        # the topic's type is the master's to say; without it, every message type
        assert "std_msgs/String" in complete(capsys, "topic", "pub", "/t", "")


def test_a_master_that_trickles_its_answer_cannot_hold_completion(
    monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    # each byte comes within the sockets' timeout: only the deadline's alarm ends the wait
    stop, answering = threading.Event(), threading.Event()
    with socket.socket() as listener:
        listener.bind(("127.0.0.1", 0))
        listener.listen(1)
        listener.settimeout(0.1)

        def trickle() -> None:
            while not stop.is_set():  # polled: a completer that never calls must not hang this
                with contextlib.suppress(TimeoutError):
                    conn, _ = listener.accept()
                    answering.set()
                    break
            if not answering.is_set():
                return
            with conn, contextlib.suppress(OSError):  # the client gone: the trickle is over
                conn.sendall(b"HTTP/1.1 200 OK\r\nContent-Length: 100000\r\n\r\n")
                while not stop.wait(0.05):
                    conn.sendall(b" ")

        thread = threading.Thread(target=trickle, daemon=True)
        thread.start()
        monkeypatch.setenv("ROS_MASTER_URI", f"http://127.0.0.1:{listener.getsockname()[1]}")
        monkeypatch.setenv("ROSTOOLS_COMPLETE_DEADLINE", "0.3")
        started = time.monotonic()
        try:
            assert complete(capsys, "topic", "echo", "/") == []
            took = time.monotonic() - started
        finally:
            stop.set()
            thread.join()
    assert answering.is_set()
    assert took < 5, took  # the trickle goes on until the test stops it
