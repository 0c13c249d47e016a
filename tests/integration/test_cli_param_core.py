"""``rostools core`` and ``rostools param`` as a user runs them."""

from __future__ import annotations

import json
import signal
import time
import xmlrpc.client
from pathlib import Path

from tests.support.env import run_cli
from tests.support.load import scaled
from tests.support.procs import free_port, master_answers, silent_port, start_cli, wait_for


def test_core_prints_its_uri_sets_params_and_stops_on_sigterm(cli_env: dict[str, str]) -> None:
    port = free_port()
    bare = {k: v for k, v in cli_env.items() if k != "ROS_IP"}  # a bare core: loopback only
    proc = start_cli("core", "-p", str(port), env=bare)
    try:
        wait_for(lambda: master_answers(f"http://127.0.0.1:{port}/"), 15, "core")
        cli_env["ROS_MASTER_URI"] = f"http://127.0.0.1:{port}"
        assert run_cli("param", "get", "/rosdistro", env=cli_env).stdout == "'noetic\n\n  '\n\n"
        names = run_cli("param", "list", env=cli_env).stdout.split()
        assert names == ["/rosdistro", "/rosversion", "/run_id"]
        again = run_cli("core", "-p", str(port), env=cli_env)
        assert again.returncode == 1 and "a master is already running" in again.stderr
        proc.signal(signal.SIGTERM)
        assert proc.popen.wait(10) == 0
        out, err = proc.output()
        assert f"ROS_MASTER_URI=http://localhost:{port}/" in out
        assert "Traceback" not in err
    finally:
        proc.stop()


def test_param_round_trips(rostools_master: str, cli_env: dict[str, str], tmp_path: Path) -> None:
    def cli(*args: str, stdin: str | None = None) -> str:
        out = run_cli("param", *args, env=cli_env, input=stdin)
        assert out.returncode == 0, out.stderr
        return out.stdout

    cli("set", "/robot", "{name: r2, gains: {p: 1.5, i: 0}, joints: [a, b]}")
    cli("set", "/robot/gains", "{d: 0.1}")  # a mapping updates, keeps p and i
    assert cli("get", "/robot/gains") == "d: 0.1\ni: 0\np: 1.5\n\n"
    cli("set", "/neg", "-5")
    cli("set", "/angle", "deg(180)")
    cli("set", "/empty", "")
    assert cli("get", "/neg") == "-5\n"
    assert cli("get", "/angle") == "3.141592653589793\n"
    assert cli("get", "/empty") == "''\n\n"
    assert json.loads(cli("get", "/robot", "-F", "json"))["joints"] == ["a", "b"]
    (tmp_path / "t.txt").write_text("line1\nline2\n")
    cli("set", "/text", "-t", str(tmp_path / "t.txt"))
    (tmp_path / "b.bin").write_bytes(b"\x00\x01\xff")
    cli("set", "/blob", "--binfile", str(tmp_path / "b.bin"))
    assert "!!binary" in cli("get", "/blob")
    cli("delete", "/robot/joints")
    assert "/robot/joints" not in cli("list").split()
    dump = tmp_path / "dump.yaml"
    cli("dump", str(dump), "/robot")
    cli("delete", "/robot")
    cli("load", str(dump), "/copy")
    assert cli("list", "/copy").split() == [
        "/copy/gains/d",
        "/copy/gains/i",
        "/copy/gains/p",
        "/copy/name",
    ]
    cli("load", "-", stdin="a: 1\n---\n_ns: deep\nb: 2\n")
    assert cli("get", "/deep/b") == "2\n" and cli("get", "/a") == "1\n"
    cli("delete", "/")
    assert cli("list") == "\n"


def test_param_errors(rostools_master: str, cli_env: dict[str, str]) -> None:
    cases = [
        (["get", "/nope"], 3, "parameter /nope is not set"),
        (["delete", "/nope"], 3, "parameter /nope is not set"),
        (["set", "/big", "3000000000"], 2, "does not fit in 32 bits"),
        (["set", "/bad", "{a: 1"], 2, "bad YAML"),
        (["set", "/x"], 2, "give exactly one of"),
        (["load", "/no/such/file.yaml"], 3, "does not exist"),
    ]
    for args, code, text in cases:
        out = run_cli("param", *args, env=cli_env)
        assert (out.returncode, text in out.stderr) == (code, True), (args, out.stderr)
        assert len(out.stderr.strip().splitlines()) == 1 and "Traceback" not in out.stderr


def test_unreachable_master_fails_fast(cli_env: dict[str, str]) -> None:
    cli_env["ROS_MASTER_URI"] = f"http://127.0.0.1:{free_port()}"
    start = time.monotonic()
    out = run_cli("param", "list", env=cli_env)
    assert out.returncode == 4
    assert "cannot reach the master at" in out.stderr
    assert time.monotonic() - start < scaled(5)
    # A master that accepts the connection but never answers: the timeout path.
    with silent_port() as port:
        cli_env["ROS_MASTER_URI"] = f"http://127.0.0.1:{port}"
        cli_env["ROSTOOLS_MASTER_TIMEOUT"] = "0.5"
        start = time.monotonic()
        out = run_cli("param", "get", "/x", env=cli_env)
    assert out.returncode == 5, out.stderr
    assert "did not answer getParam within 0.5 s" in out.stderr
    assert time.monotonic() - start < scaled(5)


def test_namespace_and_master_uri_option(rostools_master: str, cli_env: dict[str, str]) -> None:
    cli_env["ROS_NAMESPACE"] = "/robot"
    assert run_cli("param", "set", "speed", "3", env=cli_env).returncode == 0
    del cli_env["ROS_NAMESPACE"]
    master_uri = cli_env.pop("ROS_MASTER_URI")
    out = run_cli("--master-uri", master_uri, "param", "get", "/robot/speed", env=cli_env)
    assert out.stdout == "3\n", out.stderr
    assert (
        run_cli(
            "--master-uri", master_uri, "param", "list", "-F", "json", env=cli_env
        ).stdout.count("/robot/speed")
        == 1
    )


def rosout_ready(master: xmlrpc.client.ServerProxy) -> bool:
    """Whether the core's /rosout has made its last registration (a logger service)."""
    services = dict(master.getSystemState("/probe")[2][2])
    return services.get("/rosout/set_logger_level") == ["/rosout"]


def test_core_rosout_steps_aside_for_a_new_rosout(rostools_master: str) -> None:
    """Another node registering as /rosout makes the master shut ours down; ours then leaves."""
    master = xmlrpc.client.ServerProxy(rostools_master)
    wait_for(lambda: rosout_ready(master), 10, "the core's /rosout to finish registering")
    old_uri = master.lookupNode("/probe", "/rosout")[2]
    master.registerSubscriber("/rosout", "/rosout", "rosgraph_msgs/Log", "http://127.0.0.1:9/")

    def old_gone() -> bool:
        try:
            xmlrpc.client.ServerProxy(old_uri).getPid("/probe")
        except OSError:
            return True
        return False

    wait_for(old_gone, 10, "the replaced /rosout to close its XML-RPC server")
    publishers, subscribers, _ = master.getSystemState("/probe")[2]
    assert "/rosout_agg" not in dict(publishers)
    assert dict(subscribers)["/rosout"] == ["/rosout"]  # ours took none of the newcomer's away
    assert master.lookupNode("/probe", "/rosout")[2] == "http://127.0.0.1:9/"


def test_core_rosout_comes_back_after_node_kill(
    rostools_master: str, cli_env: dict[str, str]
) -> None:
    """roscore's launch file respawns rosout; so does rostools core."""
    master = xmlrpc.client.ServerProxy(rostools_master)
    wait_for(lambda: rosout_ready(master), 10, "the core's /rosout to finish registering")
    old_uri = master.lookupNode("/probe", "/rosout")[2]
    killed = run_cli("node", "kill", "/rosout", env=cli_env)
    assert killed.returncode == 0, killed.stderr

    def respawned() -> bool:
        code, _, uri = master.lookupNode("/probe", "/rosout")
        return code == 1 and uri != old_uri

    wait_for(respawned, 10, "a new /rosout")
    publishers = dict(master.getSystemState("/probe")[2][0])
    assert publishers["/rosout_agg"] == ["/rosout"]
