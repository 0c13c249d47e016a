"""``__ns:=`` on the command line puts a tool's relative names in that namespace, as rosgraph.

rosgraph's ``script_resolve_name`` reads ``__ns:=`` from ``sys.argv`` before
``ROS_NAMESPACE``; ours used ``ROS_NAMESPACE`` alone, so ``pub rm2 ... __ns:=/robot``
published on ``/rm2``.
"""

from __future__ import annotations

import pytest

from tests.support.env import needs_ros1, run_cli
from tests.support.procs import Proc, start_cli, wait_for


def _topics(env: dict[str, str]) -> list[str]:
    return run_cli("topic", "list", env=env).stdout.split()


def test_pub_echo_and_param_join_the_namespace(
    rostools_master: str, cli_env: dict[str, str]
) -> None:
    pub = start_cli("topic", "pub", "rm2", "std_msgs/String", "hi", "__ns:=/robot", env=cli_env)
    try:
        wait_for(lambda: "/robot/rm2" in _topics(cli_env), 15, "/robot/rm2")
        assert "/rm2" not in _topics(cli_env)
        echo = run_cli("topic", "echo", "rm2", "-n", "1", "--timeout", "10", "__ns:=/robot",
                       "-F", "json", env=cli_env)  # fmt: skip
        assert (echo.returncode, echo.stdout) == (0, '{"data":"hi"}\n'), echo.stderr
        info = run_cli("topic", "info", "rm2", "__ns:=/robot", env=cli_env)
        assert info.stdout.startswith("Type: std_msgs/String\n"), info.stderr
    finally:
        pub.stop()
    assert run_cli("param", "set", "p", "7", "__ns:=/robot", env=cli_env).returncode == 0
    assert run_cli("param", "get", "/robot/p", env=cli_env).stdout == "7\n"
    assert run_cli("param", "get", "p", "__ns:=/robot", env=cli_env).stdout == "7\n"
    assert run_cli("param", "get", "p", "__ns:=/elsewhere", env=cli_env).returncode == 3


@pytest.mark.interop
@needs_ros1
def test_rostopic_pub_joins_it_the_same(rostools_master: str, cli_env: dict[str, str]) -> None:
    ros_env = dict(cli_env, ROS_HOME=cli_env["HOME"])
    theirs = Proc(["rostopic", "pub", "rm3", "std_msgs/String", "hi", "__ns:=/robot"],
                  env=ros_env)  # fmt: skip
    ours = start_cli("topic", "pub", "rm4", "std_msgs/String", "hi", "__ns:=/robot", env=cli_env)
    try:
        wait_for(lambda: {"/robot/rm3", "/robot/rm4"} <= set(_topics(cli_env)), 30, "both")
        assert not {"/rm3", "/rm4"} & set(_topics(cli_env))
    finally:
        theirs.stop()
        ours.stop()
