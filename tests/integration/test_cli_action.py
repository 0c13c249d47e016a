"""``rostools action`` end to end: our master, a server written with rostools.action, the CLI.

The server (``tests/support/rt_nodes/rt_actions.py``) serves actionlib/TestAction on /fib;
the goal's number picks the outcome. One master and one server serve the whole module.
"""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from tests.support.env import run_cli
from tests.support.load import scaled
from tests.support.procs import Proc, core_and_env, start_cli, wait_for

ROOT = Path(__file__).resolve().parent.parent.parent
SERVER = ROOT / "tests" / "support" / "rt_nodes" / "rt_actions.py"


@pytest.fixture(scope="module")
def env(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, str]]:
    tmp = tmp_path_factory.mktemp("action")
    core, env = core_and_env(tmp)
    server = Proc([sys.executable, str(SERVER)], env=env)
    try:
        server.expect("ready", 20)
        wait_for(lambda: "/fib" in run_cli("action", "list", env=env).stdout, 10, "/fib")
        yield env
    finally:
        server.stop()
        core.stop()


def events(stdout: str) -> list[dict[str, Any]]:
    return [json.loads(line) for line in stdout.splitlines()]


def last_line(stderr: str) -> str:
    assert "Traceback" not in stderr, stderr
    return stderr.splitlines()[-1]


def test_list_info_and_completion(env: dict[str, str]) -> None:
    listed = json.loads(run_cli("action", "list", "-F", "json", env=env).stdout)
    assert listed == [
        {"name": "/fib", "type": "actionlib/TestAction", "servers": ["/rt_actions"], "clients": []}
    ]
    info = json.loads(run_cli("action", "info", "/fib", "-F", "json", env=env).stdout)
    assert info["goal"]["fields"] == [{"name": "goal", "type": "int32"}]
    assert info["feedback"]["fields"] == [{"name": "feedback", "type": "int32"}]
    text = run_cli("action", "info", "fib", env=env).stdout
    assert "Type: actionlib/TestAction\n" in text and "Servers:\n * /rt_actions\n" in text

    def complete(*words: str) -> list[str]:
        argv = ["__complete", "bash", str(len(words)), "rostools", *words]
        return run_cli(*argv, env=env).stdout.splitlines()

    assert complete("action", "send-goal", "/f") == ["/fib\tactionlib/TestAction"]
    assert complete("action", "send-goal", "/fib", "") == ['"{goal: 0}"\tYAML template']


def test_outcomes_and_exit_codes(env: dict[str, str]) -> None:
    done = run_cli("action", "send-goal", "/fib", "{goal: 3}", "--feedback", "-F", "json", env=env)
    assert done.returncode == 0, done.stderr
    got = events(done.stdout)
    assert [e["event"] for e in got][:1] == ["goal"] and got[0]["goal"] == {"goal": 3}
    assert [e["feedback"]["feedback"] for e in got if e["event"] == "feedback"] == [1, 2, 3]
    assert got[-1] | {"goal_id": ""} == {
        "event": "result", "goal_id": "", "status": "SUCCEEDED", "text": "",
        "result": {"result": 30},
    }  # fmt: skip
    assert got[0]["goal_id"].startswith("/rostools_action_")
    text = run_cli("action", "send-goal", "/fib", "2", env=env)  # positional, text output
    assert (text.returncode, text.stdout) == (0, "result: 20\n")
    aborted = run_cli("action", "send-goal", "/fib", "--", "-4", env=env)
    assert aborted.returncode == 7
    assert last_line(aborted.stderr).endswith("of /fib was aborted (negative goal -4)")
    rejected = run_cli("action", "send-goal", "/fib", "{goal: 13}", env=env)
    assert rejected.returncode == 8 and "was rejected (unlucky)" in last_line(rejected.stderr)
    for argv, code, says in (
        (["send-goal", "/fib", "{nope: 1}"], 2, "no field named nope in actionlib/TestGoal"),
        (["send-goal", "/nosuch", "1"], 3, "unknown action /nosuch"),
        (["cancel", "/fib"], 2, "give a goal id or --all"),
    ):
        bad = run_cli("action", *argv, env=env)
        assert bad.returncode == code and says in bad.stderr, bad.stderr
        assert bad.stderr.count("\n") == 1


def test_timeout_cancels_and_another_client_preempts(env: dict[str, str]) -> None:
    # long enough to connect on a loaded machine, far short of the goal's 50 s
    limit = round(scaled(0.6), 1)
    late = run_cli("action", "send-goal", "/fib", "1000", "--timeout", str(limit), "-F", "json",
                   env=env)  # fmt: skip
    assert late.returncode == 5, late.stderr
    assert f"did not finish within {limit:g} s; canceled it" in last_line(late.stderr)
    got = events(late.stdout)
    assert {"event": "cancel", "goal_id": got[0]["goal_id"], "reason": "timeout"} in got
    assert got[-1]["status"] == "PREEMPTED" and got[-1]["result"]["result"] > 0
    table = json.loads(run_cli("action", "status", "/fib", "--once", "-F", "json", env=env).stdout)
    assert {"goal_id": got[0]["goal_id"], "status": "PREEMPTED"} in [
        {k: g[k] for k in ("goal_id", "status")} for g in table["goals"]
    ]
    # a goal canceled by someone else: exit 9
    sender = start_cli("action", "send-goal", "/fib", "1000", "-F", "json", env=env)
    try:
        goal_id = json.loads(sender.expect('"ACTIVE"', 20))["goal_id"]
        canceled = run_cli("action", "cancel", "/fib", "--all", "-F", "json", env=env)
        assert canceled.returncode == 0, canceled.stderr
        rows = json.loads(canceled.stdout)
        assert [r["goal_id"] for r in rows] == [goal_id]
        assert rows[0]["status"] in ("PREEMPTING", "PREEMPTED")
        assert sender.popen.wait(10) == 9
        assert "was canceled: PREEMPTED" in last_line(sender.output()[1])
    finally:
        sender.stop()


def test_types_learnt_from_the_server(env: dict[str, str], tmp_path: Path) -> None:
    """A type installed only beside the server: the CLI learns it from the connections."""
    (tmp_path / "tut" / "action").mkdir(parents=True)
    (tmp_path / "tut" / "action" / "Count.action").write_text(
        "int32 goal  # how far\n---\nint32 result\n---\nint32 feedback\n"
    )
    server = Proc(
        [sys.executable, str(SERVER), "/count", "tut/CountAction", str(tmp_path)], env=env
    )
    try:
        server.expect("ready", 20)
        wait_for(lambda: "/count" in run_cli("action", "list", env=env).stdout, 10, "/count")
        info = json.loads(run_cli("action", "info", "/count", "-F", "json", env=env).stdout)
        assert info["type"] == "tut/CountAction"
        assert info["goal"] is None  # only a client's goal publisher could tell; none yet
        assert info["result"]["fields"] == [{"name": "result", "type": "int32"}]
        done = run_cli("action", "send-goal", "/count", "2", "-f", "-F", "json", env=env)
        assert done.returncode == 0, done.stderr
        got = events(done.stdout)
        assert [e["feedback"] for e in got if e["event"] == "feedback"] == [
            {"feedback": 1}, {"feedback": 2},
        ]  # fmt: skip
        assert got[-1]["result"] == {"result": 20}
    finally:
        server.stop()


def test_list_runs_without_typer_and_prints_what_typer_prints(env: dict[str, str]) -> None:
    for args in (
        ["action", "list"],
        ["action", "list", "-t"],
        ["--format", "json", "action", "list"],
    ):
        quick = run_cli(*args, env=env)
        slow = run_cli(*args, env=env | {"ROSTOOLS_NO_QUICK": "1"})
        assert (quick.returncode, quick.stdout, quick.stderr) == (0, slow.stdout, slow.stderr)
    listed = run_cli("action", "list", "-t", env=env).stdout.splitlines()
    assert "/fib [actionlib/TestAction]" in listed
    imports = subprocess.run(
        [sys.executable, "-X", "importtime", "-m", "rostools", "action", "list"],
        env=env, capture_output=True, text=True, check=True,
    ).stderr  # fmt: skip
    assert "| typer" not in imports  # Typer alone is 50 ms of start-up
