"""``rostools tf echo`` live on ``rostools core``, with rostools' own publishers only."""

from __future__ import annotations

import json

from tests.support.env import run_cli
from tests.support.procs import start_cli

STATIC = (
    "{transforms: [{header: {frame_id: base}, child_frame_id: cam,"
    " transform: {translation: {x: 1}, rotation: {w: 1}}}]}"
)


def test_a_publisher_of_something_else_on_tf_is_skipped_and_said_once(
    rostools_master: str, cli_env: dict[str, str]
) -> None:
    static = start_cli("topic", "pub", "/tf_static", "tf2_msgs/TFMessage", STATIC, env=cli_env)
    wrong = start_cli(
        "topic", "pub", "-r", "20", "/tf", "std_msgs/String", "data: hi", "__name:=wrong",
        env=cli_env,
    )  # fmt: skip
    try:
        done = run_cli(
            "tf", "echo", "base", "cam", "-r", "20", "-n", "10", "--timeout", "60", "-F", "json",
            env=cli_env, timeout=90,
        )  # fmt: skip
    finally:
        wrong.stop()
        static.stop()
    assert done.returncode == 0, done.stderr
    records = [json.loads(line) for line in done.stdout.splitlines()]
    answers = [r for r in records if "event" not in r]
    assert len(answers) == 10 and answers[0]["translation"] == [1.0, 0.0, 0.0]
    # the String publisher may not have been connected yet; if it was, one line says so, and
    # the JSON stream carries it as an event among the answers
    skipped = [line for line in done.stderr.splitlines() if "does not decode" in line]
    assert len(skipped) <= 1 and all("/wrong" in line for line in skipped)
    events = [r for r in records if "event" in r]
    assert [e["event"] for e in events] == ["message_skipped"] * len(skipped)


def test_waiting_with_no_transform_at_all_times_out_with_tf2s_words(
    rostools_master: str, cli_env: dict[str, str]
) -> None:
    done = run_cli("tf", "echo", "map", "base", "--timeout", "1", env=cli_env)
    assert done.returncode == 5
    assert done.stderr.count("\n") == 1
    assert "within 1 s" in done.stderr and "does not exist" in done.stderr
