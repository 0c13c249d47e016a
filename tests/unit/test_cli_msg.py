"""``rostools msg`` from the command line: output, formats and exit codes."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from tests.support.env import CORPUS, needs_corpus, run_cli


def test_show_expands_nested_types(cli_env: dict[str, str]) -> None:
    out = run_cli("msg", "show", "geometry_msgs/PointStamped", env=cli_env)
    assert out.returncode == 0, out.stderr
    assert out.stdout == (
        "std_msgs/Header header\n  uint32 seq\n  time stamp\n  string frame_id\n"
        "geometry_msgs/Point point\n  float64 x\n  float64 y\n  float64 z\n\n"
    )


def test_show_bare_name_and_service(cli_env: dict[str, str]) -> None:
    out = run_cli("msg", "show", "SetBool", env=cli_env)
    assert out.stdout.startswith("[std_srvs/SetBool]:\nbool data\n---\nbool success\n")
    assert run_cli("msg", "md5", "std_srvs/SetBool", env=cli_env).stdout == (
        "09fb03525b03e7ea1fd3992bafd87e16\n"
    )


def test_json_output(cli_env: dict[str, str]) -> None:
    out = run_cli("msg", "show", "std_msgs/Header", "--format", "json", env=cli_env)
    data = json.loads(out.stdout)
    assert data["md5sum"] == "2176decaecbce78abc3b96ef049fabed"
    assert [f["name"] for f in data["fields"]] == ["seq", "stamp", "frame_id"]
    listing = json.loads(run_cli("--format", "json", "msg", "list", env=cli_env).stdout)
    assert "sensor_msgs/Image" in listing
    md5s = json.loads(run_cli("msg", "md5", "String", "-F", "json", env=cli_env).stdout)
    assert {"type": "std_msgs/String", "md5sum": "992ce8a1687cec8c8bd883ec73ca41d1"} in md5s


def test_list_package_packages(cli_env: dict[str, str]) -> None:
    assert "std_srvs/Trigger" in run_cli("msg", "list", "--srv", env=cli_env).stdout.split()
    pkg = run_cli("msg", "package", "std_msgs", "-s", env=cli_env).stdout
    assert pkg.startswith("std_msgs/Bool std_msgs/Byte")
    assert "geometry_msgs" in run_cli("msg", "packages", env=cli_env).stdout.split()


def test_proto(cli_env: dict[str, str]) -> None:
    assert run_cli("msg", "proto", "geometry_msgs/Vector3", env=cli_env).stdout == (
        '"x: 0.0\ny: 0.0\nz: 0.0"\n'
    )
    flow = run_cli("msg", "proto", "std_srvs/SetBool", "-f", "1", "--no-quotes", env=cli_env)
    assert flow.stdout == "{data: false}\n"


@pytest.mark.parametrize(
    ("args", "code", "message"),
    [
        (["msg", "show", "nope/Nope"], 3, "unknown type nope/Nope"),
        (["msg", "md5", "NoSuchTypeAnywhere"], 3, "no message or service named NoSuchTypeAnywhere"),
        (["msg", "show", "std_msgs::String"], 2, "invalid type"),
        (["msg", "package", "no_pkg"], 3, "no package named no_pkg holds message or service"),
        (["msg", "show", "--bag", "/nonexistent.bag", "x/Y"], 3, "no such file"),
    ],
)
def test_errors_are_one_line_with_exit_codes(
    cli_env: dict[str, str], args: list[str], code: int, message: str
) -> None:
    out = run_cli(*args, env=cli_env)
    assert out.returncode == code
    assert message in out.stderr
    assert len(out.stderr.strip().splitlines()) == 1
    assert "Traceback" not in out.stderr


def test_info_is_show(cli_env: dict[str, str]) -> None:
    """``rosmsg info`` is rosmsg's alias of show; ours too."""
    shown = run_cli("msg", "show", "geometry_msgs/Pose", env=cli_env)
    assert run_cli("msg", "info", "geometry_msgs/Pose", env=cli_env).stdout == shown.stdout != ""


def test_a_package_of_services_only_has_no_message_types(cli_env: dict[str, str]) -> None:
    """As rosmsg: ``msg package -s std_srvs`` prints an empty line and exits 0 (it exited 3)."""
    out = run_cli("msg", "package", "-s", "std_srvs", env=cli_env)
    assert (out.returncode, out.stdout, out.stderr) == (0, "\n", "")


def test_custom_package_and_malformed_msg(cli_env: dict[str, str], tmp_path: Path) -> None:
    (tmp_path / "my_pkg" / "msg").mkdir(parents=True)
    (tmp_path / "my_pkg" / "msg" / "Good.msg").write_text('string S="hi"\nint32 x\n')
    (tmp_path / "my_pkg" / "msg" / "Bad.msg").write_text("int32 x y z\n")
    good = run_cli("msg", "show", "my_pkg/Good", "--msg-path", str(tmp_path), env=cli_env)
    assert good.stdout == 'string S="hi"\nint32 x\n\n'
    cli_env["ROSTOOLS_MSG_PATH"] = str(tmp_path)
    bad = run_cli("msg", "md5", "my_pkg/Bad", env=cli_env)
    assert bad.returncode == 1
    assert "my_pkg/Bad: line 1: invalid declaration" in bad.stderr
    assert "Traceback" not in bad.stderr


@pytest.mark.parametrize(
    "args",
    [
        ["msg", "show", "loops/Self"],
        ["msg", "show", "loops/Self", "--format", "json"],
        ["msg", "info", "loops/Pair"],
        ["msg", "proto", "loops/Self"],
        ["msg", "show", "loops/Holder"],
        ["msg", "md5", "loops/Self"],
    ],
)
def test_a_type_that_contains_itself_is_one_line(
    cli_env: dict[str, str], tmp_path: Path, args: list[str]
) -> None:
    """show, info and proto refuse it as md5 does (they recursed to a RecursionError)."""
    (tmp_path / "loops" / "msg").mkdir(parents=True)
    (tmp_path / "loops" / "srv").mkdir()
    (tmp_path / "loops" / "msg" / "Self.msg").write_text("loops/Self next\nint32 x\n")
    (tmp_path / "loops" / "msg" / "Pair.msg").write_text("loops/Other other\n")
    (tmp_path / "loops" / "msg" / "Other.msg").write_text("loops/Pair pair\n")
    (tmp_path / "loops" / "srv" / "Holder.srv").write_text("loops/Self a\n---\nint32 b\n")
    cli_env["ROSTOOLS_MSG_PATH"] = str(tmp_path)
    out = run_cli(*args, env=cli_env)
    assert out.returncode == 1
    assert out.stdout == ""
    assert "contains itself" in out.stderr
    assert len(out.stderr.strip().splitlines()) == 1, out.stderr


def test_type_from_stdin(cli_env: dict[str, str]) -> None:
    out = run_cli("msg", "md5", env=cli_env, input="\nstd_msgs/Header\n")
    assert out.stdout == "2176decaecbce78abc3b96ef049fabed\n"


def test_fast_path_matches_typer_path(cli_env: dict[str, str]) -> None:
    for name in ("std_msgs/String", "String", "std_srvs/SetBool", "nope/X"):
        fast = run_cli("msg", "md5", name, env=cli_env)
        slow = run_cli("msg", "md5", name, env=cli_env | {"ROSTOOLS_NO_QUICK": "1"})
        assert (fast.returncode, fast.stdout, fast.stderr) == (
            slow.returncode,
            slow.stdout,
            slow.stderr,
        )


@needs_corpus
def test_show_from_bag(cli_env: dict[str, str]) -> None:
    bag = CORPUS / "ros1" / "matlab_rosbag" / "constants.bag"
    out = run_cli("msg", "show", "-b", str(bag), "test_roscpp_serialization/Constants", env=cli_env)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith("uint8 a=1\nint8 b=2\n")


def test_show_from_mcap(cli_env: dict[str, str], tmp_path: Path) -> None:
    from mcap.writer import Writer

    path = tmp_path / "one.mcap"
    with path.open("wb") as f:
        w = Writer(f)
        w.start(profile="ros1", library="test")
        sid = w.register_schema(
            "my_pkg/Thing",
            "ros1msg",
            b"# c\nint32 x\nstd_msgs/Header h\n"
            + b"=" * 80
            + b"\nMSG: std_msgs/Header\nuint32 seq\ntime stamp\n",
        )
        w.register_channel("/thing", "ros1", sid, {"md5sum": "x"})
        w.finish()
    out = run_cli("msg", "show", "-b", str(path), "my_pkg/Thing", env=cli_env)
    assert out.returncode == 0, out.stderr
    assert out.stdout == "int32 x\nstd_msgs/Header h\n  uint32 seq\n  time stamp\n\n"
    raw = run_cli("msg", "show", "-r", "-b", str(path), "Thing", env=cli_env)
    assert raw.stdout == "# c\nint32 x\nstd_msgs/Header h\n"


def test_show_action_from_a_file_and_from_the_table(
    cli_env: dict[str, str], tmp_path: Path
) -> None:
    folder = tmp_path / "ws" / "tut" / "action"
    folder.mkdir(parents=True)
    (folder / "Fib.action").write_text("int32 order\n---\nint32[] sequence\n---\nint32[] partial\n")
    ws = str(tmp_path / "ws")
    out = run_cli("msg", "show", "tut/action/Fib", "--msg-path", ws, env=cli_env)
    assert out.stdout == "int32 order\n---\nint32[] sequence\n---\nint32[] partial\n\n", out.stderr
    data = json.loads(run_cli("msg", "show", "tut/FibAction", "--msg-path", ws, "-F", "json",
                              env=cli_env).stdout)  # fmt: skip
    assert data["kind"] == "action" and data["feedback"]["fields"][0]["name"] == "partial"
    assert len(data["messages"]) == 7 and data["md5sum"] == data["messages"]["tut/FibAction"]
    # the wrapper message is still there by its msg/ name; the built-in table has actionlib's
    wrapper = run_cli("msg", "show", "actionlib/msg/TestAction", env=cli_env).stdout
    assert wrapper.startswith("actionlib/TestActionGoal action_goal\n")
    test = run_cli("msg", "show", "actionlib/TestAction", env=cli_env).stdout
    assert test == "int32 goal\n---\nint32 result\n---\nint32 feedback\n\n"
    assert run_cli("msg", "proto", "actionlib/Test.action", env=cli_env).stdout == '"goal: 0"\n'
