"""Services between rostools and real rospy/roscpp, on both masters."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

from tests.conftest import MasterInfo
from tests.support.env import needs_ros1, run_cli
from tests.support.procs import Proc, start_ros1_node, wait_for

pytestmark = [pytest.mark.interop, needs_ros1]

RT_SERVICES = Path(__file__).parent.parent / "support" / "rt_nodes" / "rt_services.py"


def ros(info: MasterInfo, *argv: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        list(argv), env=info.ros_env, capture_output=True, text=True, timeout=60, check=False
    )


def test_rostools_calls_a_rospy_server(any_master: MasterInfo) -> None:
    server = start_ros1_node("add_two_ints_server.py", [], any_master.ros_env)
    env = any_master.cli_env
    try:
        server.expect("ready", 30)
        # rospy registers services in the background: "ready" can come before the master knows.
        wait_for(
            lambda: "/trigger" in run_cli("service", "list", env=env).stdout, 20, "rospy services"
        )
        first = run_cli("service", "call", "/add_two_ints", "{a: 1, b: 2}", env=env)
        assert first.stdout == "sum: 3\n", first.stderr
        assert run_cli("service", "call", "/add_two_ints", "--", "-7", "3", env=env).returncode == 1
        failed = run_cli("service", "call", "/add_two_ints", "{a: -7, b: 3}", env=env)
        assert failed.returncode == 1
        assert "service cannot process request: negative sum -4" in failed.stderr
        assert (
            run_cli("service", "type", "/add_two_ints", env=env).stdout
            == "rospy_tutorials/AddTwoInts\n"
        )
        out = run_cli("service", "call", "/trigger", env=env).stdout
        assert out == 'success: True\nmessage: "triggered 1"\n'
        ours = run_cli("service", "info", "/trigger", env=env).stdout
        theirs = ros(any_master, "rosservice", "info", "/trigger").stdout
        assert ours == theirs
        assert (
            run_cli("service", "list", env=env).stdout
            == ros(any_master, "rosservice", "list").stdout
        )
    finally:
        server.stop()


def test_real_clients_reach_a_rostools_server(any_master: MasterInfo) -> None:
    server = Proc([sys.executable, str(RT_SERVICES)], env=any_master.cli_env)
    try:
        server.expect("ready", 30)
        call = ros(any_master, "rosservice", "call", "/set_bool", "data: true")
        assert call.stdout == 'success: True\nmessage: "set True"\n', call.stderr
        assert ros(any_master, "rosservice", "type", "/trigger").stdout == "std_srvs/Trigger\n"
        info = ros(any_master, "rosservice", "info", "/set_bool").stdout
        assert "Node: /rt_services\n" in info and "Type: std_srvs/SetBool\nArgs: data\n" in info
        assert "/add_two_ints" in ros(any_master, "rosservice", "list").stdout.split()
        proxy = start_ros1_node("service_proxy_client.py", ["5"], any_master.ros_env)
        try:
            answers = [proxy.expect("answer", 30) for _ in range(5)]
            assert [a.split()[1] for a in answers] == ["True", "False", "True", "False", "True"]
            assert proxy.expect("trigger", 10).strip() == "trigger triggered 1"
        finally:
            proxy.stop()
    finally:
        server.stop()


@pytest.mark.parametrize(
    ("mode", "code", "text"),
    [
        ("ok", 0, ""),
        ("fail", 1, "failed: (no reason given)"),
        ("throw", 1, "failed: add_two_ints_server was told to throw"),
    ],
)
def test_rostools_calls_a_roscpp_server(
    any_master: MasterInfo, mode: str, code: int, text: str
) -> None:
    from tests.support.cppbuild import build, cpp_missing

    if (reason := cpp_missing()) is not None:
        pytest.skip(reason)
    server = Proc([str(build("add_two_ints_server")), "--mode", mode], env=any_master.ros_env)
    try:
        server.expect("ready", 30)
        out = run_cli("service", "call", "/add_two_ints", "{a: 40, b: 2}", env=any_master.cli_env)
        assert out.returncode == code, out.stderr
        if code == 0:
            assert out.stdout == "sum: 42\n"
            server.expect("request 40 2", 10)
        else:
            assert text in out.stderr
    finally:
        server.stop()
