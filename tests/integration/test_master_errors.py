"""Every command meets a master the same way: one policy, whichever client it uses (issue 12)."""

from __future__ import annotations

import socket
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.support.env import run_cli
from tests.support.procs import silent_port

COMMANDS = [
    (["param", "get", "/x"], "getParam"),  # the blocking client
    (["topic", "list"], "getSystemState"),
    (["topic", "pub", "-1", "/x", "std_msgs/Empty", "{}"], "getTopicTypes"),  # type check
    (["topic", "echo", "/x"], "getTopicTypes"),
    (["service", "call", "/s"], "lookupService"),
    (["bag", "record", "-O", "{tmp}/x.bag", "/x"], "hasParam"),  # the node: /use_sim_time
]


@pytest.fixture
def silent_master(cli_env: dict[str, str]) -> Iterator[str]:
    """A master that accepts connections and never answers."""
    with silent_port() as port:
        cli_env["ROS_MASTER_URI"] = f"http://127.0.0.1:{port}"
        cli_env["ROSTOOLS_MASTER_TIMEOUT"] = "0.5"
        yield cli_env["ROS_MASTER_URI"]


@pytest.mark.parametrize(("args", "method"), COMMANDS, ids=[" ".join(c[:2]) for c, _ in COMMANDS])
def test_a_master_that_does_not_answer_is_a_timeout(
    args: list[str], method: str, silent_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    # The node's calls said "cannot reach" and exit 4 where the blocking client said exit 5.
    done = run_cli(*(a.replace("{tmp}", str(tmp_path)) for a in args), env=cli_env, timeout=20)
    assert done.returncode == 5, done.stderr
    last = done.stderr.splitlines()[-1]  # bag record says "Recording to ..." first
    assert last == f"rostools: the master at {silent_master} did not answer {method} within 0.5 s"


@pytest.mark.parametrize(("args", "method"), COMMANDS, ids=[" ".join(c[:2]) for c, _ in COMMANDS])
def test_a_master_that_is_not_there_is_unreachable(
    args: list[str], method: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    args = [a.replace("{tmp}", str(tmp_path)) for a in args]
    done = run_cli(*args, env=cli_env, timeout=20)  # cli_env: the discard port, refused
    assert done.returncode == 4, done.stderr
    # One reason for one cause: the node said "connection refused", the client "Connection..."
    assert done.stderr.splitlines()[-1].startswith(
        "rostools: cannot reach the master at http://127.0.0.1:9: connection refused"
    ), done.stderr


@pytest.fixture(params=["HTTP/1.1 500 Internal Server Error", "HTTP/1.1 200 OK"])
def odd_master(request: pytest.FixtureRequest, cli_env: dict[str, str]) -> Iterator[str]:
    """A master that answers every call with an error page (500) or with XML that is no answer."""
    body = b"<html>no</html>" if "500" in request.param else b"<methodResponse></methodResponse>"
    answer = f"{request.param}\r\nContent-Length: {len(body)}\r\n\r\n".encode() + body
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen(16)

    def serve() -> None:
        while True:
            try:
                conn, _ = server.accept()
            except OSError:
                return  # closed: the test is over
            with conn:
                conn.recv(65536)
                conn.sendall(answer)

    threading.Thread(target=serve, daemon=True).start()
    cli_env["ROS_MASTER_URI"] = f"http://127.0.0.1:{server.getsockname()[1]}"
    yield cli_env["ROS_MASTER_URI"]
    server.close()


@pytest.mark.parametrize(("args", "method"), COMMANDS, ids=[" ".join(c[:2]) for c, _ in COMMANDS])
def test_a_master_that_answers_oddly_is_a_bad_answer(
    args: list[str], method: str, odd_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    # the defect: the node's calls (bag record) took a non-200 or a malformed answer for an
    # internal error, where the blocking client said "bad answer"; one policy serves both now
    done = run_cli(*(a.replace("{tmp}", str(tmp_path)) for a in args), env=cli_env, timeout=20)
    assert done.returncode == 1, done.stderr
    last = done.stderr.splitlines()[-1]
    assert last.startswith(f"rostools: bad answer from the master at {odd_master}"), last
    assert "internal error" not in done.stderr and "Traceback" not in done.stderr
