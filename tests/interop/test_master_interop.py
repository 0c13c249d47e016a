"""The bundled master with real ROS 1 nodes and tools, and rostools param on a real roscore."""

from __future__ import annotations

import re
import subprocess
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.conftest import MasterInfo
from tests.support.env import CLI, needs_ros1, run_cli
from tests.support.procs import (
    Proc,
    free_port,
    ros_env,
    start_ros1_node,
    start_roscore,
    start_rostools_core,
)

pytestmark = [pytest.mark.interop, needs_ros1]


def ros_tool(info: MasterInfo, *argv: str, stdin: str | None = None) -> str:
    """Run a real ROS 1 command-line tool against the master; its stdout."""
    proc = subprocess.run(
        list(argv),
        env=info.ros_env,
        capture_output=True,
        text=True,
        input=stdin,
        timeout=60,
        check=False,
    )
    return proc.stdout + (f"[exit {proc.returncode}] {proc.stderr}" if proc.returncode else "")


def normalize(text: str) -> str:
    """Hide what differs between any two runs: ports, pids, uuids, anonymous suffixes."""
    text = re.sub(r"http://[\w.-]+:\d+/?", "http://HOST:PORT/", text)
    text = re.sub(r"rosrpc://[\w.-]+:\d+", "rosrpc://HOST:PORT", text)
    text = re.sub(r"[0-9a-f]{8}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{4}-[0-9a-f]{12}", "UUID", text)
    text = re.sub(r"_\d+_\d{10,}", "_ANON", text)
    text = re.sub(r"Pid: \d+", "Pid: N", text)
    return text


@pytest.fixture
def talker_listener(any_master: MasterInfo) -> Iterator[tuple[Proc, Proc]]:
    talker = start_ros1_node("talker.py", ["/chatter", "20"], any_master.ros_env)
    listener = start_ros1_node(
        "listener.py", ["/chatter", "std_msgs/String", "__name:=listener"], any_master.ros_env
    )
    try:
        yield talker, listener
    finally:
        talker.stop()
        listener.stop()


def test_rospy_talker_and_listener_exchange_messages(
    any_master: MasterInfo, talker_listener: tuple[Proc, Proc]
) -> None:
    _, listener = talker_listener
    listener.expect(r"got hello \d+", timeout=20)
    listener.expect(r"got hello \d+", timeout=5)


def test_roscpp_nodes_register_and_connect(any_master: MasterInfo, tmp_path: Path) -> None:
    """roscpp's rosout node subscribes to a rospy talker's /rosout and republishes it."""
    env = any_master.ros_env
    # Under its own name and output, beside the master's own /rosout, so that only the C++
    # node can have delivered what the listener hears.
    cpp_rosout = ["/usr/lib/rosout/rosout", "__name:=rosout_cpp", "/rosout_agg:=/rosout_cpp"]
    nodes = [
        start_ros1_node("listener.py", ["/rosout_cpp", "rosgraph_msgs/Log"], env),
        Proc(cpp_rosout, env=env),
        start_ros1_node("talker.py", ["/chatter", "20"], env),
    ]
    bag = tmp_path / "rec.bag"
    recorder = Proc(
        ["/usr/lib/rosbag/record", "-O", str(bag), "/chatter", "__name:=record"], env=env
    )
    try:
        nodes[0].expect(r"got said hello \d+", timeout=20)  # talker -> rosout (C++) -> listener
        state = ros_tool(any_master, "rostopic", "info", "/chatter")
        assert "* /record (" in state  # the C++ recorder registered as a subscriber
    finally:
        recorder.stop()
        for node in nodes:
            node.stop()


def test_real_tools_answer_the_same_on_both_masters(
    tmp_path: Path, cli_env: dict[str, str]
) -> None:
    outputs: dict[str, list[str]] = {}
    for kind in ("rostools", "roscore"):
        port = free_port()
        uri = f"http://127.0.0.1:{port}"
        env = ros_env(uri, tmp_path / kind)
        cli_env["ROS_MASTER_URI"] = uri
        master = (
            start_rostools_core(port, cli_env) if kind == "rostools" else start_roscore(port, env)
        )
        info = MasterInfo(kind, uri, env, cli_env)
        # One after the other: the order they register in is the order tools list them.
        listener = start_ros1_node(
            "listener.py", ["/chatter", "std_msgs/String", "__name:=listener"], env
        )
        talker: Proc | None = None
        params = tmp_path / f"{kind}.yaml"
        params.write_text("gains: {p: 1.5, i: 0}\nname: r2\nlist: [1, 2.5, x]\n")
        dump = tmp_path / f"{kind}-dump.yaml"
        try:
            listener.expect("ready", timeout=20)
            talker = start_ros1_node("talker.py", ["/chatter", "20"], env)
            listener.expect("got hello", timeout=20)
            runs = [
                ros_tool(info, "rostopic", "list"),
                ros_tool(info, "rostopic", "info", "/chatter"),
                ros_tool(info, "rostopic", "type", "/chatter"),
                ros_tool(info, "rosnode", "list"),
                ros_tool(info, "rosnode", "info", "-q", "/talker"),
                ros_tool(info, "rostopic", "info", "/rosout"),
                ros_tool(info, "rosparam", "set", "/robot", "{a: 1, b: [x, 2]}"),
                ros_tool(info, "rosparam", "set", "/robot/c", "-3.5"),
                ros_tool(info, "rosparam", "get", "/robot"),
                ros_tool(info, "rosparam", "load", str(params), "/loaded"),
                ros_tool(info, "rosparam", "get", "/loaded/list"),
                # real rosparam dump has no "-" for stdout: it writes a file of that name
                ros_tool(info, "rosparam", "dump", str(dump), "/loaded") + dump.read_text(),
                ros_tool(info, "rosparam", "delete", "/loaded/gains"),
                ros_tool(info, "rosparam", "list", "/loaded"),
                ros_tool(info, "rosparam", "get", "/nope"),
            ]
            outputs[kind] = [normalize(r) for r in runs]
        finally:
            if talker is not None:
                talker.stop()
            listener.stop()
            master.stop()
    for ours, theirs in zip(outputs["rostools"], outputs["roscore"], strict=True):
        assert ours == theirs


def test_param_subscriptions_receive_updates(any_master: MasterInfo) -> None:
    watcher = start_ros1_node("param_watch.py", ["/gain"], any_master.ros_env)
    try:
        watcher.expect("value None", timeout=20)
        assert run_cli("param", "set", "/gain", "2.5", env=any_master.cli_env).returncode == 0
        watcher.expect(r"value 2\.5", timeout=10)
        assert run_cli("param", "set", "/", "{gain: 7}", env=any_master.cli_env).returncode == 0
        watcher.expect("value 7", timeout=10)
        assert run_cli("param", "delete", "/gain", env=any_master.cli_env).returncode == 0
        watcher.expect("value None", timeout=10)
    finally:
        watcher.stop()


def test_rostools_param_matches_rosparam_on_a_real_roscore(
    tmp_path: Path, cli_env: dict[str, str]
) -> None:
    port = free_port()
    uri = f"http://127.0.0.1:{port}"
    env = ros_env(uri, tmp_path / "home")
    cli_env["ROS_MASTER_URI"] = uri
    master = start_roscore(port, env, launch=True)  # roscore itself, roslaunch and all
    info = MasterInfo("roscore", uri, env, cli_env)
    yaml_file = tmp_path / "p.yaml"
    yaml_file.write_text("a: 1\nb: {c: [1, 2], d: x}\n---\n_ns: sub\ne: deg(90)\n")
    steps: list[tuple[list[str], str | None]] = [
        (["set", "NS/x", "{y: 1, z: [a, 2.0]}"], None),
        (["set", "NS/neg", "-7"], None),
        (["set", "NS/s", "'123'"], None),
        (["set", "NS/e", "1e3"], None),
        (["set", "NS/r", "rad(pi/4)"], None),
        (["get", "NS/x"], None),
        (["get", "NS/neg"], None),
        (["get", "NS/s"], None),
        (["get", "NS/e"], None),
        (["get", "NS/r"], None),
        (["get", "NS"], None),
        (["load", str(yaml_file), "NS/loaded"], None),
        (["load", "-", "NS/stdin"], "k: v\n"),
        (["list", "NS"], None),
        (["dump", "DUMPFILE", "NS/loaded"], None),
        (["delete", "NS/x/y"], None),
        (["get", "NS/x"], None),
    ]
    try:
        for args, stdin in steps:
            ours_args = [
                a.replace("NS", "/ours").replace("DUMPFILE", str(tmp_path / "o.yaml")) for a in args
            ]
            theirs_args = [
                a.replace("NS", "/theirs").replace("DUMPFILE", str(tmp_path / "t.yaml"))
                for a in args
            ]
            ours = run_cli("param", *ours_args, env=cli_env, input=stdin)
            assert ours.returncode == 0, (args, ours.stderr)
            theirs = ros_tool(info, "rosparam", *theirs_args, stdin=stdin)
            assert ours.stdout.replace("/ours", "NS") == theirs.replace("/theirs", "NS"), args
        assert (tmp_path / "o.yaml").read_text() == (tmp_path / "t.yaml").read_text()
    finally:
        master.stop()


def test_text_that_is_not_utf8_is_refused_as_rosparam_refuses_it(
    any_master: MasterInfo, tmp_path: Path
) -> None:
    """``param load`` stored U+FFFD for the bad bytes and exited 0; rosparam fails, sets nothing.

    rosparam's ``load FILE`` and ``set -t FILE`` end in a UnicodeDecodeError (exit 1); ours say
    which byte in one line (exit 2, as ``topic pub -f``). From stdin too: ours reads bytes.
    """
    bad = tmp_path / "bad.yaml"
    bad.write_bytes(b"good: 1\nname: r\xff2\n")
    env = any_master.cli_env
    theirs = [
        ros_tool(any_master, "rosparam", "load", str(bad), "/theirs"),
        ros_tool(any_master, "rosparam", "set", "-t", str(bad), "/theirs_text"),
    ]
    assert all(t.startswith("[exit 1]") and "UnicodeDecodeError" in t for t in theirs), theirs
    ours = [
        run_cli("param", "load", str(bad), "/ours", env=env),
        run_cli("param", "set", "-t", str(bad), "/ours_text", env=env),
        subprocess.run(
            [*CLI, "param", "load", "-", "/ours_stdin"],
            input=bad.read_bytes(),
            capture_output=True,
            env=env,
            timeout=60,
            check=False,
        ),
    ]
    for run, source in zip(ours, [str(bad), str(bad), "stdin"], strict=True):
        err = run.stderr if isinstance(run.stderr, str) else run.stderr.decode()
        assert (run.returncode, err) == (2, f"rostools: {source} is not UTF-8 text (byte 15)\n")
    listed = run_cli("param", "list", env=env).stdout.split()
    assert not [name for name in listed if name.startswith(("/ours", "/theirs"))]
