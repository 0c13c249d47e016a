"""Every command of the tree, run for real with ``--format json``: valid JSON, one way or the other.

The tree is ``rostools/cli/tree.json`` (generated from the app, and checked fresh by the
completion tests). A command added without a recipe here fails ``test_every_command_has_a_recipe``.
"""

from __future__ import annotations

import json
import signal
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml

from rostools.cli.completer import load_tree
from tests.support.bagdata import write_sample
from tests.support.env import CLI, run_cli
from tests.support.procs import Proc, core_and_env, free_port, start_cli, wait_for

ROOT = Path(__file__).resolve().parent.parent.parent

#: Commands that print no data (they act, or print a script): no --format to test.
NOT_DATA = {
    "topic pub",
    "tf pub",
    "log set",
    "param set",
    "param delete",
    "param load",
    "completion show",
    "demo",
}

#: Commands that run until stopped and serve each other: ``test_snapshot_and_trigger``.
TOGETHER = {"bag snapshot", "bag trigger"}

#: Servers that run until stopped, whose JSON is read by their own tests (``core`` below,
#: ``bridge`` in test_bridge.py, whose every test reads its events).
SERVERS = {"core", "bridge"}

#: command -> its arguments; ``{bag}``, ``{tmp}`` are filled in. ``-F json`` is added.
RECIPES: dict[str, list[str]] = {
    "topic list": ["-v"],
    "topic info": ["/chatter_demo"],
    "topic find": ["std_msgs/String"],
    "topic type": ["/stamped/header"],
    "topic echo": ["/stamped", "-n", "2"],
    "topic hz": ["/chatter_demo", "--timeout", "1.5"],
    "topic bw": ["/chatter_demo", "--timeout", "1.5"],
    "topic delay": ["/stamped", "--timeout", "1.5"],
    "topic plot": ["/stamped/point/x", "-n", "2"],
    "action list": ["-t"],
    "action info": ["/fib"],
    "action send-goal": ["/fib", "{goal: 2}", "--feedback"],
    "action cancel": ["/fib", "--all"],
    "action status": ["/fib", "--once"],
    "service list": ["-n"],
    "service info": ["/add_two_ints"],
    "service type": ["/add_two_ints"],
    "service find": ["std_srvs/Trigger"],
    "service uri": ["/add_two_ints"],
    "service node": ["/add_two_ints"],
    "service args": ["/add_two_ints"],
    "service call": ["/add_two_ints", "{a: 1, b: 2}"],
    "param list": [],
    "param get": ["/demo"],
    "param dump": ["-"],
    "msg show": ["geometry_msgs/PoseStamped"],
    "msg info": ["geometry_msgs/PoseStamped"],
    "msg md5": ["std_srvs/Trigger"],
    "msg list": [],
    "msg package": ["std_msgs"],
    "msg packages": [],
    "msg proto": ["geometry_msgs/Point"],
    "node list": ["-a"],
    "node info": ["/rosout"],
    "node ping": ["/rosout", "-c", "2"],
    "node kill": ["/victim"],
    "node machine": [],
    "node cleanup": ["--dry-run"],
    "node graph": [],
    "tf echo": ["map", "base", "-n", "1"],
    "log echo": ["--level", "debug", "-n", "1"],
    "log list": ["/rosout"],
    "log get": ["/rosout"],
    "tf frames": ["-w", "1"],
    "tf monitor": ["-n", "1"],
    "bag info": ["{bag}", "--freq"],
    "bag filter": ["{bag}", "{tmp}/filtered.mcap", "topic == '/count'"],
    "bag convert": ["{bag}", "{tmp}/converted.mcap"],
    "bag compress": ["{tmp}/copy.bag"],
    "bag decompress": ["{tmp}/copy.bag", "-f"],
    "bag recover": ["{bag}", "{tmp}/recovered.bag"],
    "bag reindex": ["{tmp}/copy.bag", "-f"],
    "bag play": ["{bag}", "-i", "-d", "0"],
    "bag record": ["/chatter_demo", "-l", "2", "-O", "{tmp}/rec.bag"],
    "bag merge": ["{tmp}/merged.mcap", "{bag}", "{bag}"],
    "bag export": ["{bag}", "-o", "{tmp}/dataset", "--force"],
    "bag split": ["{bag}", "--count", "100", "-o", "{tmp}/part.bag", "-f"],
    "bag cat": ["{bag}", "-n", "3"],
    "bag plot": ["{bag}", "/point/x", "/count/data"],
    "bag doctor": ["{bag}"],
    "bag attachments": ["{bag}"],
    "bag metadata": ["{bag}"],
    "completion install": ["fish"],
    "doctor": [],
}


def commands() -> list[str]:
    found = []
    for group, node in load_tree()["commands"].items():
        if "commands" in node:
            found += [f"{group} {name}" for name in node["commands"]]
        else:
            found.append(group)
    return found


def test_every_command_has_a_recipe() -> None:
    missing = set(commands()) - RECIPES.keys() - NOT_DATA - TOGETHER - SERVERS
    assert not missing, f"add a --format json recipe for: {sorted(missing)}"
    assert not (RECIPES.keys() - set(commands())), "recipes for commands that do not exist"


def parse(text: str) -> list[Any]:
    """One JSON document, or NDJSON: one document per line. Raises on anything else."""
    try:
        return [json.loads(text)]
    except json.JSONDecodeError:
        return [json.loads(line) for line in text.splitlines() if line.strip()]


@pytest.fixture(scope="module")
def graph(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[dict[str, str], Path]]:
    """A master with a talker, a stamped topic, services, parameters and a node to kill."""

    tmp = tmp_path_factory.mktemp("tree")
    core, env = core_and_env(tmp)
    pub = [*CLI, "topic", "pub"]
    procs = [
        Proc([*pub, "-r", "20", "/chatter_demo", "std_msgs/String", "data: x"], env=env),
        Proc(
            [*pub, "-r", "20", "/stamped", "geometry_msgs/PointStamped", "{header: auto}"], env=env
        ),
        Proc([*pub, "/victim_topic", "std_msgs/Empty", "{}", "__name:=victim"], env=env),
        Proc([sys.executable, str(ROOT / "tests/support/rt_nodes/rt_services.py")], env=env),
        Proc([sys.executable, str(ROOT / "tests/support/rt_nodes/rt_actions.py")], env=env),
        Proc([*CLI, "tf", "pub", "0", "0", "1", "0", "0", "0", "map", "base"], env=env),
        Proc([*pub, "-r", "5", "/rosout", "rosgraph_msgs/Log", "{level: 4, msg: hi}"], env=env),
    ]
    try:
        assert run_cli("param", "set", "/demo", "{a: 1, b: [x, y]}", env=env).returncode == 0
        wait_for(lambda: len(run_cli("topic", "list", env=env).stdout.split()) >= 5, 20, "graph")
        wait_for(lambda: "/add_two_ints" in run_cli("service", "list", env=env).stdout, 20, "srv")
        wait_for(lambda: "/fib" in run_cli("action", "list", env=env).stdout, 20, "action")
        wait_for(lambda: "/tf_static" in run_cli("topic", "list", env=env).stdout, 20, "tf")
        write_sample(tmp / "sample.bag", 400)
        yield env, tmp
    finally:
        for proc in procs:
            proc.stop()
        core.stop()


@pytest.mark.parametrize("command", sorted(RECIPES))
def test_format_json_is_valid_json(command: str, graph: tuple[dict[str, str], Path]) -> None:
    env, tmp = graph
    if command in ("bag compress", "bag decompress", "bag reindex"):
        (tmp / "copy.bag").write_bytes((tmp / "sample.bag").read_bytes())
    args = [
        a.replace("{bag}", str(tmp / "sample.bag")).replace("{tmp}", str(tmp))
        for a in RECIPES[command]
    ]
    done = run_cli(*command.split(), *args, "-F", "json", env=env, timeout=60)
    assert done.returncode == 0, done.stderr
    documents = parse(done.stdout)
    assert documents, f"{command} printed nothing"


def test_snapshot_and_trigger(graph: tuple[dict[str, str], Path]) -> None:
    env, tmp = graph
    snap = start_cli("bag", "snapshot", "/chatter_demo", "-F", "json", "__name:=snap_tree",
                     env=env, cwd=tmp)  # fmt: skip
    try:
        wait_for(lambda: "/snap_tree/trigger" in run_cli("service", "list", env=env).stdout, 20)
        done = run_cli("bag", "trigger", "/snap_tree", "--after", "0.2", "-F", "json", env=env)
        assert done.returncode == 0, done.stderr
        (summary,) = parse(done.stdout)
        assert summary["messages"] > 0 and (tmp / summary["name"]).is_file()
        snap.signal(signal.SIGINT)
        assert snap.popen.wait(20) == 0
        events = [doc["event"] for doc in parse(snap.output()[0])]
        assert events == ["writing", "written", "stopped"]
    finally:
        snap.stop()


def test_core_format_json(graph: tuple[dict[str, str], Path]) -> None:
    env, _ = graph
    port = free_port()
    # with every flag of roscore's: a script written for roscore must not die on a usage error
    roscore_flags = ["-v", "-w", "3", "-t", "4", "--master-logger-level", "warn",
                     "--sigint-timeout", "5", "--sigterm-timeout", "2"]  # fmt: skip
    core = start_cli("core", "-p", str(port), "-F", "json", *roscore_flags, env=env)
    try:
        line = core.expect(r"^\{", timeout=20)
        assert json.loads(line)["uri"].endswith(f":{port}/")
    finally:
        assert core.stop() == 0


def test_core_format_yaml_is_yaml(graph: tuple[dict[str, str], Path]) -> None:
    # the defect: core printed JSON for --format yaml
    env, _ = graph
    port = free_port()
    core = start_cli("core", "-p", str(port), "-F", "yaml", env=env)
    try:
        line = core.expect(r"^uri: ", timeout=20)
        assert yaml.safe_load(line)["uri"].endswith(f":{port}/")
    finally:
        assert core.stop() == 0


@pytest.mark.parametrize(
    "args",
    [["topic", "hz", "--tcpnodelay", "/x"], ["topic", "delay", "--tcpnodelay", "/x"]],
    ids=["hz", "delay"],
)
def test_rostopic_flags_are_taken(args: list[str], cli_env: dict[str, str]) -> None:
    """rostopic's ``--tcpnodelay`` parses (it was a usage error); no master here, so exit 4."""
    done = run_cli(*args, env=cli_env, timeout=30)
    assert done.returncode == 4, done.stderr
