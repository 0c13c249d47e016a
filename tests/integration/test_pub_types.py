"""``topic pub`` of a type other than the topic's: one warning, and ``-1`` fails if nobody took it.

It printed "publishing" and exited 0 while every subscriber refused the messages; rospy
only logs "topic types do not match" on the publisher's side.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support.env import needs_ros1, run_cli
from tests.support.procs import Proc, start_cli, wait_for


def test_another_type_is_said_and_once_fails(rostools_master: str, cli_env: dict[str, str]) -> None:
    talker = start_cli("topic", "pub", "/chatter", "std_msgs/String", "hi", env=cli_env)
    listener = start_cli("topic", "echo", "/chatter", env=cli_env)
    try:
        listener.expect("hi", 20)
        done = run_cli("topic", "pub", "/chatter", "std_msgs/Int32", "5", "-1", env=cli_env)
    finally:
        listener.stop()
        talker.stop()
    assert done.returncode == 1, done.stderr
    lines = done.stderr.splitlines()
    assert lines[0] == (
        "WARNING: /chatter carries std_msgs/String, not std_msgs/Int32: its subscribers will "
        "refuse these messages"
    )
    assert any(line.startswith("WARNING: /rostools_echo_") and "refused the messages" in line
               for line in lines), lines  # fmt: skip
    assert lines[-1].startswith("rostools: no subscriber of /chatter took the message: ")


def test_once_with_nobody_listening_is_still_fine(
    rostools_master: str, cli_env: dict[str, str]
) -> None:
    done = run_cli("topic", "pub", "/lonely", "std_msgs/Int32", "5", "-1", env=cli_env)
    assert (done.returncode, done.stderr) == (
        0,
        "publishing and latching message for 3.0 seconds\n",
    )
    wait_for(lambda: "/lonely" not in run_cli("topic", "list", env=cli_env).stdout, 10, "gone")


@needs_ros1
@pytest.mark.interop
def test_pub_says_what_rostopic_says(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    # -v -1 said "publishing data: ..." then "publishing and latching message ..."; a file of
    # one message with -r said nothing
    one = tmp_path / "one.yaml"
    one.write_text("data: a\n")  # with a trailing ---, rostopic counts an empty second one
    ros_env = dict(cli_env, ROS_HOME=str(tmp_path), PYTHONUNBUFFERED="1")
    for argv in (["-v", "-1", "/x", "std_msgs/String", "hi"],
                 ["-f", str(one), "-r", "5", "/y", "std_msgs/String"]):  # fmt: skip
        theirs = Proc(["rostopic", "pub", *argv], env=ros_env)
        ours = start_cli("topic", "pub", *argv, env=cli_env)
        try:
            said = theirs.expect("publishing", 30).rstrip("\n")
            # ours says it on stderr, with the other status lines
            wait_for(lambda s=said, p=ours: s in _stderr_so_far(p), 30, f"ours to say {said!r}")
        finally:
            theirs.stop()
            ours.stop()


def _stderr_so_far(proc: Proc) -> str:
    """What ``proc`` wrote on stderr so far (a pipe: read what is there without blocking)."""
    import os

    assert proc.popen.stderr is not None
    fd = proc.popen.stderr.fileno()
    os.set_blocking(fd, False)
    chunk = proc.popen.stderr.read() or b""
    proc.seen.append(chunk.decode(errors="replace"))
    return "".join(proc.seen)
