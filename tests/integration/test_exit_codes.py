"""The exit codes of docs/scripting.md, case by case, from real runs: one line, no traceback."""

from __future__ import annotations

import signal
from pathlib import Path

import pytest

from rostools.errors import EXIT_CODES
from tests.support.bagdata import write_sample
from tests.support.env import run_cli
from tests.support.fakepeer import FakeNode
from tests.support.procs import start_cli, wait_for

CODES = {name: code for code, name, _ in EXIT_CODES}


def one_line(stderr: str) -> None:
    assert stderr.count("\n") == 1 and stderr.startswith("rostools: "), stderr
    assert "Traceback" not in stderr


@pytest.mark.parametrize(
    ("name", "argv"),
    [
        ("usage", ["topic", "list", "--no-such-flag"]),
        ("usage", ["topic", "pub", "/t", "std_msgs/Int32", "data: [1"]),
        ("usage", ["bag", "record"]),
        ("not found", ["msg", "show", "nosuch_msgs/Nothing"]),
        ("not found", ["bag", "info", "no-such-file.bag"]),
        ("unreachable", ["topic", "list"]),
        ("unreachable", ["param", "get", "/x"]),
    ],
)
def test_offline_exit_codes(name: str, argv: list[str], cli_env: dict[str, str]) -> None:
    done = run_cli(*argv, env=cli_env)  # cli_env's master is the discard port: nobody there
    assert done.returncode == CODES[name], done.stderr
    one_line(done.stderr)


def test_live_exit_codes(rostools_master: str, cli_env: dict[str, str], tmp_path: Path) -> None:
    ok = run_cli("topic", "list", env=cli_env)
    assert ok.returncode == CODES["ok"]
    for name, argv in (
        ("not found", ["topic", "info", "/nosuch"]),
        ("not found", ["param", "get", "/nosuch"]),
        ("not found", ["node", "kill", "/nosuch"]),
        ("timeout", ["topic", "echo", "/nosuch", "-n", "1", "--timeout", "1"]),
        ("timeout", ["service", "call", "/nosuch", "--wait", "--timeout", "1"]),
    ):
        done = run_cli(*argv, env=cli_env)
        assert done.returncode == CODES[name], (argv, done.stderr)
        one_line(done.stderr.splitlines(keepends=True)[-1])


def test_error_and_data_loss(cli_env: dict[str, str], tmp_path: Path) -> None:
    text = tmp_path / "notes.bag"
    text.write_text("not a bag\n")
    done = run_cli("bag", "info", str(text), env=cli_env)
    assert done.returncode == CODES["error"]
    one_line(done.stderr)
    sample = write_sample(tmp_path / "s.bag", 2000, compression="bz2", chunk_size=20_000)
    cut = tmp_path / "cut.bag"
    cut.write_bytes(sample.path.read_bytes()[: sample.path.stat().st_size * 2 // 3])
    done = run_cli("bag", "recover", str(cut), env=cli_env)
    assert done.returncode == CODES["data loss"], done.stderr
    assert "lost" in done.stderr.splitlines()[-1]


def test_interrupted_wait_is_130(cli_env: dict[str, str]) -> None:
    # A master that lists no service: its second getSystemState says the wait has begun.
    with FakeNode({"getSystemState": lambda caller: [1, "", [[], [], []]]}) as master:
        cli_env["ROS_MASTER_URI"] = master.uri
        waiting = start_cli("service", "call", "/nosuch", "--wait", "--timeout", "60", env=cli_env)
        try:
            wait_for(lambda: master.asked("getSystemState") >= 2, 15, "the wait")
            waiting.signal(signal.SIGINT)
            assert waiting.popen.wait(10) == CODES["interrupted"]
            _, err = waiting.output()
            assert "Traceback" not in err
        finally:
            waiting.stop()


def test_a_value_that_reads_debug_is_a_value(cli_env: dict[str, str]) -> None:
    # the defect (found by the long fuzz run, seed 710018): 'param set /x --debug' with no
    # master printed a traceback, as though --debug had been given before the group name
    done = run_cli("param", "set", "/fuzzed", "--debug", env=cli_env)
    assert done.returncode == 4, done.stderr
    assert "Traceback" not in done.stderr and done.stderr.count("\n") == 1, done.stderr
    debug = run_cli("--debug", "param", "set", "/fuzzed", "1", env=cli_env)
    assert debug.returncode == 4 and "Traceback" in debug.stderr
