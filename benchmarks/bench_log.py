"""``rostools log echo`` beside ``rosconsole echo`` at 10k log messages a second.

A roscpp publisher (``peers/log_flood.cpp``) sends rosgraph_msgs/Log at WARN on /rosout_agg,
10,000 a second for ``RUN`` seconds, on a neutral rosmaster. Each tool follows the topic with
its text printed to a file; we count the lines it printed of those sent, and the CPU seconds
it used. Both run in the same benchmark run, one after the other, on the same master.
"""

from __future__ import annotations

import json
import subprocess
import tempfile
import time
import xmlrpc.client
from pathlib import Path

from benchmarks.common import (
    Result,
    cpp_peer,
    cpu_seconds,
    have,
    master,
    ros_env,
    rostools_cmd,
    start,
    stop,
)

PEERS = Path(__file__).with_name("peers")
RATE = 10_000
RUN = 5.0  # seconds of publishing
TOPIC = "/rosout_agg"


def _subscribed(uri: str) -> bool:
    state = xmlrpc.client.ServerProxy(uri).getSystemState("/bench")[2]
    return any(topic == TOPIC and nodes for topic, nodes in state[1])


def _one(argv: list[str], uri: str, flood: str) -> tuple[float, float]:
    """(fraction of the messages printed, CPU seconds) for one echo command."""
    env = ros_env(uri)
    count = int(RATE * RUN)
    with tempfile.TemporaryFile() as out:
        echo = start(argv, env, stdout=out, stderr=subprocess.DEVNULL)
        try:
            deadline = time.monotonic() + 30
            while not _subscribed(uri):
                if time.monotonic() > deadline or echo.poll() is not None:
                    raise RuntimeError(f"{argv[:3]} did not subscribe")
                time.sleep(0.05)
            pub = start([flood, TOPIC, str(RATE), str(count)], env, stdout=subprocess.PIPE)
            try:
                text, _ = pub.communicate(timeout=RUN * 6 + 30)
            finally:
                stop(pub)
            sent = json.loads(text.decode().splitlines()[-1])["published"]
            time.sleep(2)  # what is queued reaches the echo (the publisher stayed up 2 s)
            cpu = cpu_seconds(echo.pid)
        finally:
            stop(echo)
        out.seek(0)
        printed = sum(1 for line in out if b"flood " in line)
    return printed / sent, cpu


def bench() -> list[Result]:
    """Fraction printed and CPU seconds, ours beside rosconsole's."""
    flood = cpp_peer("log_flood", PEERS)
    ours_argv = [*rostools_cmd(), "log", "echo", "--topic", TOPIC, "-l", "warn", "--nocolor"]
    theirs_argv = ["rosconsole", "echo", "--topic", TOPIC, "-l", "warn", "--nocolor"]
    with master() as uri:
        ours = _one(ours_argv, uri, flood)
        theirs = _one(theirs_argv, uri, flood) if have("rosconsole") else None
    note = f"{RATE:,} msgs/s for {RUN:g} s of rosgraph_msgs/Log at WARN from roscpp"
    return [
        Result(
            "log echo 10k/s: fraction printed",
            "fraction",
            ours[0],
            theirs[0] if theirs else None,
            ">= rosconsole",
            None if theirs is None else ours[0] >= theirs[0],
            note,
        ),
        Result(
            "log echo 10k/s: CPU per message printed",
            "us",
            ours[1] / max(ours[0] * RATE * RUN, 1) * 1e6,
            theirs[1] / max(theirs[0] * RATE * RUN, 1) * 1e6 if theirs else None,
            "<= rosconsole",
            None
            if theirs is None
            else ours[1] / max(ours[0], 1e-9) <= theirs[1] / max(theirs[0], 1e-9),
            note,
        ),
        Result(
            "log echo 10k/s: CPU seconds",
            "s",
            ours[1],
            theirs[1] if theirs else None,
            "<= rosconsole",
            None if theirs is None else ours[1] <= theirs[1],
            note,
        ),
    ]


BENCHMARKS = {"log_echo": bench}
