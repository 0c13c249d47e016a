"""The topic data path and commands, beside rospy and rostopic in one run."""

from __future__ import annotations

import json
import subprocess
import time
from pathlib import Path

from benchmarks.common import (
    BENCH_VENV,
    SYSTEM_PYTHON,
    Result,
    have,
    master,
    ros_env,
    rostools_cmd,
    start,
    stop,
    time_commands,
)

PEERS = Path(__file__).with_name("peers")
SECONDS = 4.0


def _throughput(pub_argv: list[str], sub_argv: list[str], env: dict[str, str]) -> dict[str, float]:
    """Start a subscriber and a publisher; the subscriber's count."""
    sub = start(sub_argv, env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
    time.sleep(1.0)
    pub = start(pub_argv, env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        out, _ = sub.communicate(timeout=SECONDS + 30)
    finally:
        stop(pub)
        stop(sub)
    result: dict[str, float] = json.loads(out.decode().strip().splitlines()[-1])
    return result


def _pubsub(size: int) -> tuple[dict[str, float], dict[str, float] | None]:
    ours_py = str(BENCH_VENV / "bin" / "python")
    rostools_cmd()  # make sure the benchmark venv is current
    with master() as uri:
        env = ros_env(uri)
        ours = _throughput(
            [
                ours_py,
                str(PEERS / "rt_pubsub.py"),
                "pub",
                uri,
                "/bench",
                str(size),
                str(SECONDS + 5),
            ],
            [ours_py, str(PEERS / "rt_pubsub.py"), "sub", uri, "/bench", str(SECONDS)],
            env,
        )
        theirs = None
        if have("rostopic"):
            theirs = _throughput(
                [
                    SYSTEM_PYTHON,
                    str(PEERS / "rospy_pubsub.py"),
                    "pub",
                    "/bench2",
                    str(size),
                    str(SECONDS + 5),
                ],
                [SYSTEM_PYTHON, str(PEERS / "rospy_pubsub.py"), "sub", "/bench2", str(SECONDS)],
                env,
            )
    return ours, theirs


def bench_pubsub_small() -> Result:
    ours, theirs = _pubsub(100)
    rate = ours["messages"] / ours["seconds"]
    ref = theirs["messages"] / theirs["seconds"] if theirs else None
    return Result(
        "publisher -> subscriber, 100-byte messages",
        "msgs/s",
        rate,
        ref,
        ">= 100000 msgs/s",
        rate >= 100_000,
        "theirs: rospy publisher -> rospy subscriber",
    )


def bench_pubsub_1mb() -> Result:
    ours, theirs = _pubsub(1_000_000)
    rate = ours["bytes"] / ours["seconds"] / 1e9
    ref = theirs["bytes"] / theirs["seconds"] / 1e9 if theirs else None
    return Result(
        "publisher -> subscriber, 1 MB messages",
        "GB/s",
        rate,
        ref,
        ">= 1.5 GB/s",
        rate >= 1.5,
        "theirs: rospy publisher -> rospy subscriber",
    )


def bench_topic_list() -> Result:
    with master() as uri:
        env = ros_env(uri)
        talker = (
            start(
                [
                    SYSTEM_PYTHON,
                    str(Path(__file__).parent.parent / "tests/support/ros1_nodes/talker.py"),
                ],
                env,
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
            )
            if have("rostopic")
            else None
        )
        try:
            time.sleep(2.0)
            commands = {"ours": [*rostools_cmd(), "topic", "list"]}
            if have("rostopic"):
                commands["theirs"] = ["rostopic", "list"]
            t = time_commands(commands, env=env)
        finally:
            if talker is not None:
                stop(talker)
    theirs = t.get("theirs")
    met = None if theirs is None else t["ours"] <= 0.5 * theirs
    return Result(
        "topic list (wall, whole process)",
        "ms",
        t["ours"] * 1e3,
        theirs * 1e3 if theirs else None,
        "<= 0.5x rostopic list",
        met,
    )


BENCHMARKS = {
    "topic_list": bench_topic_list,
    "pubsub_small": bench_pubsub_small,
    "pubsub_1mb": bench_pubsub_1mb,
}
