"""Tab completion in real bash, zsh and fish, with a live master and without one."""

from __future__ import annotations

import os
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from rostools.cli.completer import TREE
from rostools.cli.completion import SCRIPT_NAMES, quick_text, script, tree_text
from rostools.cli.launch import QUICK
from tests.support.env import CLI
from tests.support.procs import Proc, cpu_hogs, silent_port, start_cli, wait_for
from tests.support.shells import ROOT, Shell, shell_missing

SHELLS = [
    pytest.param(
        s, marks=pytest.mark.skipif(shell_missing(s) is not None, reason=shell_missing(s) or "")
    )
    for s in ("bash", "zsh", "fish")
]


def test_checked_in_scripts_and_tree_are_fresh() -> None:
    hint = "stale: run python -m rostools.cli.completion"
    assert TREE.read_text() == tree_text(), hint
    assert Path(QUICK).read_text() == quick_text(), hint
    for shell, name in SCRIPT_NAMES.items():
        assert (ROOT / "completions" / name).read_text() == script(shell), hint


@pytest.fixture
def graph(rostools_master: str, cli_env: dict[str, str]) -> Iterator[dict[str, str]]:
    """A publisher on /chatter_demo and the test services on the master."""
    procs = [
        start_cli("topic", "pub", "-r", "5", "/chatter_demo", "std_msgs/String", "data: hi",
                  env=cli_env),
        start_cli("topic", "pub", "-r", "5", "/pose_demo", "geometry_msgs/PoseStamped", "{}",
                  env=cli_env),
        Proc([sys.executable, str(ROOT / "tests/support/rt_nodes/rt_services.py")], env=cli_env),
    ]  # fmt: skip
    try:
        wait_for(lambda: _registered(rostools_master), 20, "publisher and services")
        yield cli_env
    finally:
        for proc in procs:
            proc.stop()


def _registered(uri: str) -> bool:
    import xmlrpc.client

    pubs, _, services = xmlrpc.client.ServerProxy(uri).getSystemState("/t")[2]
    topics = {t for t, _ in pubs}
    return {"/chatter_demo", "/pose_demo"} <= topics and any(
        s == "/add_two_ints" for s, _ in services
    )


@pytest.fixture
def shell_in(request: pytest.FixtureRequest, tmp_path: Path) -> Iterator[object]:
    opened: list[Shell] = []

    def open_shell(name: str, env: dict[str, str]) -> Shell:
        shell = Shell(name, env, tmp_path)
        opened.append(shell)
        return shell

    yield open_shell
    for shell in opened:
        shell.close()


@pytest.mark.parametrize("shell", SHELLS)
def test_live_names_types_and_templates(
    shell: str, graph: dict[str, str], shell_in: object, tmp_path: Path
) -> None:
    sh: Shell = shell_in(shell, graph)  # type: ignore[operator]
    assert sh.complete("rostools topic ec") == "rostools topic echo"
    assert sh.complete("rostools topic echo /chatter_d") == "rostools topic echo /chatter_demo"
    assert sh.complete("rostools topic pub /chatter_demo ") == (
        "rostools topic pub /chatter_demo std_msgs/String"
    )
    assert sh.complete("rostools topic pub /chatter_demo std_msgs/String ") == (
        "rostools topic pub /chatter_demo std_msgs/String {data: ''}"
    )
    # field paths, as topic echo and topic type take them
    assert sh.complete("rostools topic echo /pose_demo/po") == "rostools topic echo /pose_demo/pose"
    assert sh.complete("rostools topic type /pose_demo/pose/orie") == (
        "rostools topic type /pose_demo/pose/orientation"
    )
    assert sh.complete("rostools service call /add_t") == "rostools service call /add_two_ints"
    assert sh.complete("rostools service call /add_two_ints ") == (
        "rostools service call /add_two_ints {a: 0, b: 0}"
    )
    assert sh.complete("rostools param get /rosd") == "rostools param get /rosdistro"
    assert sh.complete("rostools --format ya") == "rostools --format yaml"


@pytest.mark.parametrize("shell", SHELLS)
def test_bag_files_offered(
    shell: str, cli_env: dict[str, str], shell_in: object, tmp_path: Path
) -> None:
    for name in ("run.bag", "trip.mcap", "notes.txt"):
        (tmp_path / name).write_text("")
    sh: Shell = shell_in(shell, cli_env)  # type: ignore[operator]
    assert sh.complete("rostools bag info ru") == "rostools bag info run.bag"
    assert sh.complete("rostools bag info no") == "rostools bag info no"  # not a bag: not offered
    shown = sh.offers("rostools bag play ", "run.bag", "trip.mcap")
    assert "run.bag" in shown and "trip.mcap" in shown and "notes.txt" not in shown


@pytest.mark.parametrize("shell", SHELLS)
def test_without_a_master_completes_offline_and_fast(
    shell: str, cli_env: dict[str, str], shell_in: object
) -> None:
    sh: Shell = shell_in(shell, cli_env)  # type: ignore[operator]  # master: the discard port
    assert sh.complete("rostools node ki") == "rostools node kill"
    assert sh.complete("rostools msg show geometry_msgs/PointSt") == (
        "rostools msg show geometry_msgs/PointStamped"
    )
    # --opt=value, which bash splits at "=": the value is completed, the option kept
    assert sh.complete("rostools topic echo --format=ya") == "rostools topic echo --format=yaml"
    assert sh.complete("rostools bag info --format=json -F te") == (
        "rostools bag info --format=json -F text"
    )
    started = time.monotonic()
    assert sh.complete("rostools topic echo /nothing_her") == "rostools topic echo /nothing_her"
    assert time.monotonic() - started < 3  # includes the harness's own settling waits


def test_a_silent_master_cannot_hold_completion_past_the_deadline(
    cli_env: dict[str, str],
) -> None:
    import subprocess

    with silent_port() as port:
        env = dict(cli_env, ROS_MASTER_URI=f"http://127.0.0.1:{port}")
        argv = [*CLI, "__complete", "bash", "3", "rostools", "topic", "echo", "/"]
        started = time.monotonic()
        done = subprocess.run(argv, env=env, capture_output=True, text=True, timeout=30)
        took = time.monotonic() - started
    assert done.returncode == 0 and done.stdout == ""
    # the master would hold it for ever; 300 ms of deadline, and the start-up (not counted)
    assert took < 10, took


#: A start-up half a second longer, for every Python the shell runs (sitecustomize is imported
#: at start-up, from PYTHONPATH first).
SLOW_START = "import time\ntime.sleep(0.5)\n"


@pytest.fixture
def busy_machine(tmp_path: Path) -> Iterator[dict[str, str]]:
    """A busy robot: two CPU hogs at normal priority for the test's length (this machine has two
    cores), and rostools' start-up 0.5 s longer. Yields what a shell's environment adds.

    The hogs alone made the start-up longer than the old 300 ms deadline under the suite's
    load, not always on a quiet machine: the longer start-up makes the test the same on both.
    """
    site = tmp_path / "slow_start"
    site.mkdir()
    (site / "sitecustomize.py").write_text(SLOW_START)
    path = os.pathsep.join(p for p in (str(site), os.environ.get("PYTHONPATH")) if p)
    with cpu_hogs(2):
        yield {"PYTHONPATH": path}


@pytest.mark.parametrize("shell", SHELLS)
def test_under_load_tab_completes_live_names(
    shell: str, graph: dict[str, str], busy_machine: dict[str, str], shell_in: object
) -> None:
    # before: the 300 ms deadline counted the interpreter's start-up, which load made longer
    # than that, and a topic's name or field was not completed
    sh: Shell = shell_in(shell, graph | busy_machine)  # type: ignore[operator]
    assert sh.complete("rostools topic echo /chatter_d") == "rostools topic echo /chatter_demo"
    assert sh.complete("rostools topic type /pose_demo/pose/orie") == (
        "rostools topic type /pose_demo/pose/orientation"
    )


@pytest.mark.parametrize("shell", SHELLS)
def test_under_load_offline_words_complete(
    shell: str, cli_env: dict[str, str], busy_machine: dict[str, str], shell_in: object
) -> None:
    # before: under load the deadline passed before the words were looked at; a command's
    # name completed only by luck, a type (whose listing takes longer) never
    sh: Shell = shell_in(shell, cli_env | busy_machine)  # type: ignore[operator]
    assert sh.complete("rostools topic ec") == "rostools topic echo"
    assert sh.complete("rostools topic echo --format=ya") == "rostools topic echo --format=yaml"
    assert sh.complete("rostools msg show geometry_msgs/PointSt") == (
        "rostools msg show geometry_msgs/PointStamped"
    )
