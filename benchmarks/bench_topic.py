"""The topic data path and commands, beside rospy and rostopic in one run."""

from __future__ import annotations

import json
import os
import subprocess
import tempfile
import time
from pathlib import Path

from benchmarks.common import (
    BENCH_VENV,
    ROOT,
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


#: Fields of the type ``pub_big_type`` publishes (``int32 f0`` ... : 400 KB a message).
BIG_FIELDS = 100_000
BIG_TARGET = 1.5  # our peak at most this many times rostopic pub's
NAME = "topic pub of 100,000 fields (peak RSS)"


def _peak_mb(argv: list[str], env: dict[str, str]) -> float:
    """The peak resident memory of one run of ``argv`` to its end (``wait4``'s ru_maxrss)."""
    with tempfile.TemporaryFile() as err:  # a pipe left unread could fill and stop it
        proc = start(argv, env, stdout=subprocess.DEVNULL, stderr=err)
        try:
            _, status, usage = os.wait4(proc.pid, 0)
        finally:
            stop(proc)
        if status != 0:
            err.seek(0)
            raise RuntimeError(f"{argv[:4]} failed: {err.read().decode()[-500:]}")
    return usage.ru_maxrss / 1024


def bench_pub_big_type() -> Result:
    """Peak memory of ``topic pub -1`` of a type of 100,000 int32 fields, beside rostopic pub.

    rostopic needs the type as a Python module: genpy generates it, and ``compileall`` compiles
    it ahead, as a catkin install would (rostopic's first run, which compiles it, is in the
    note). Issue 32: ours took 780 MB; compiling one function of 100,000 statements did it.
    """
    build = ROOT / "benchmarks" / "build" / "pub_big"
    msg_dir = build / "msgs" / "bigpkg" / "msg"
    msg_dir.mkdir(parents=True, exist_ok=True)
    (msg_dir / "Big.msg").write_text("".join(f"int32 f{i}\n" for i in range(BIG_FIELDS)))
    args = ["topic", "pub", "-1", "/big", "bigpkg/Big", "{f0: 1}"]
    with master() as uri:
        env = ros_env(uri) | {"ROSTOOLS_MSG_PATH": str(build / "msgs")}
        ours = _peak_mb([*rostools_cmd(), *args], env)
        ours_small = _peak_mb(
            [*rostools_cmd(), "topic", "pub", "-1", "/s", "std_msgs/String", "x"], env
        )
        if not have("rostopic"):
            note = f"a String: {ours_small:.0f} MB"
            return Result(NAME, "MB", ours, None, f"<= {BIG_TARGET}x rostopic pub", None, note)
        py = build / "py"
        generate = [
            SYSTEM_PYTHON, "/usr/lib/genpy/genmsg_py.py", "-p", "bigpkg",
            f"-Ibigpkg:{msg_dir}", "-o", str(py / "bigpkg" / "msg"), str(msg_dir / "Big.msg"),
        ]  # fmt: skip
        subprocess.run(generate, check=True, capture_output=True)
        (py / "bigpkg" / "__init__.py").touch()
        (py / "bigpkg" / "msg" / "__init__.py").write_text("from ._Big import *\n")
        for cached in py.rglob("*.pyc"):
            cached.unlink()
        theirs_env = env | {"PYTHONPATH": str(py), "PYTHONDONTWRITEBYTECODE": "1"}
        cold = _peak_mb(["rostopic", *args[1:]], theirs_env)
        subprocess.run([SYSTEM_PYTHON, "-m", "compileall", "-q", str(py)], check=True)
        theirs = _peak_mb(["rostopic", *args[1:]], theirs_env)
        theirs_small = _peak_mb(["rostopic", "pub", "-1", "/s", "std_msgs/String", "x"], env)
    return Result(
        NAME,
        "MB",
        ours,
        theirs,
        f"<= {BIG_TARGET}x rostopic pub",
        ours <= BIG_TARGET * theirs,
        f"theirs with the module not compiled ahead: {cold:.0f} MB; a String: ours "
        f"{ours_small:.0f} MB, theirs {theirs_small:.0f} MB",
    )


BENCHMARKS = {
    "topic_list": bench_topic_list,
    "pubsub_small": bench_pubsub_small,
    "pubsub_1mb": bench_pubsub_1mb,
    "pub_big_type": bench_pub_big_type,
}
