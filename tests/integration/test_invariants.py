"""ARCHITECTURE.md's Invariants, each held to account end to end through the command.

- "Raw frames are never decoded" on record, play, hz and bw: they work on a type whose
  definition nobody here can parse.
- "record and echo never ask for reuse_frames": big messages come out byte for byte, where a
  planted ``reuse_frames=True`` in record corrupted 15 of 142 recorded 200 KB messages.
"""

from __future__ import annotations

import json
import struct
import sys
from pathlib import Path

import pytest

from rostools.bag.formats.access import open_bag
from rostools.wire.tcpros import publisher_header
from tests.support.env import run_cli
from tests.support.fakepeer import FakePublisher, frame
from tests.support.procs import Proc, linked, start_cli, wait_for

#: 200 KB messages, each of one byte value: a frame overwritten by the next shows at once.
BIG = 70_000
COUNT = 60


def _big(i: int) -> bytes:
    """A std_msgs/String of BIG bytes, all ``chr(97 + i % 26)``."""
    return struct.pack("<I", BIG) + bytes([97 + i % 26]) * BIG


@pytest.fixture
def big_publisher(rostools_master: str, cli_env: dict[str, str]) -> Proc:
    """``rostools topic pub`` cannot make these: a script on the API publishes them, fast."""
    script = f"""
import struct, sys, time
import rostools
with rostools.Node("big_talker", sys.argv[1]) as node:
    pub = node.advertise("/big", "std_msgs/String", queue_size=1000)
    pub.wait_for_subscribers(1, timeout=30)
    print("ready", flush=True)
    sys.stdin.readline()  # the test says when
    for i in range({COUNT}):
        pub.publish(data=chr(97 + i % 26) * {BIG})
    print("sent", flush=True)
    time.sleep(30)
"""
    return Proc([sys.executable, "-c", script, rostools_master], env=cli_env, stdin=-1)


def _go(proc: Proc) -> None:
    assert proc.popen.stdin is not None
    proc.popen.stdin.write(b"go\n")
    proc.popen.stdin.flush()


def test_record_keeps_every_big_frame_intact(
    big_publisher: Proc, cli_env: dict[str, str], tmp_path: Path
) -> None:
    rec = start_cli(
        "bag", "record", "-O", "big.bag", "/big", "-l", str(COUNT), env=cli_env, cwd=tmp_path
    )
    try:
        big_publisher.expect("ready", 30)
        _go(big_publisher)
        assert rec.popen.wait(60) == 0
    finally:
        rec.stop()
        big_publisher.stop()
    with open_bag(tmp_path / "big.bag") as reader:
        got = [bytes(data) for _, _, data in reader.messages(["/big"])]
    assert len(got) == COUNT
    bad = [i for i, data in enumerate(got) if data != _big(i)]
    assert bad == [], f"{len(bad)} of {COUNT} recorded messages differ from what was sent"


def test_echo_prints_every_big_message_intact(big_publisher: Proc, cli_env: dict[str, str]) -> None:
    echo = start_cli("topic", "echo", "/big", "-n", str(COUNT), "-F", "json", env=cli_env)
    try:
        big_publisher.expect("ready", 30)
        _go(big_publisher)
        out, err = echo.output()  # read as it comes: 12 MB would fill the pipe
        assert echo.popen.returncode == 0, err
    finally:
        echo.stop()
        big_publisher.stop()
    texts = [json.loads(line)["data"] for line in out.splitlines()]
    assert len(texts) == COUNT
    bad = [i for i, text in enumerate(texts) if text != chr(97 + i % 26) * BIG]
    assert bad == [], f"{len(bad)} of {COUNT} printed messages differ from what was sent"


#: A definition no parser takes: the pass-through commands must not need one.
BROKEN = "this is { not a message definition\n"


def _broken_frames(sock: object) -> None:
    header = publisher_header("/fake", "/opaque", "0123456789abcdef0123456789abcdef",
                              "nobody_knows/Opaque", BROKEN, False)  # fmt: skip
    sock.sendall(header)  # type: ignore[attr-defined]
    import time

    for i in range(400):
        sock.sendall(frame(struct.pack("<I", i) + b"opaque" * 10))  # type: ignore[attr-defined]
        time.sleep(0.01)


@pytest.mark.parametrize("verb", ["hz", "bw"])
def test_hz_and_bw_never_decode(rostools_master: str, cli_env: dict[str, str], verb: str) -> None:
    with FakePublisher(rostools_master, "/opaque", _broken_frames, msg_type="nobody_knows/Opaque"):
        done = run_cli("topic", verb, "/opaque", "--timeout", "2.5", "-F", "json", env=cli_env)
    assert done.returncode == 0, done.stderr
    reports = [json.loads(line) for line in done.stdout.splitlines()]
    assert reports and all(r["topic"] == "/opaque" for r in reports), done.stdout


def test_record_and_play_never_decode(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    with FakePublisher(rostools_master, "/opaque", _broken_frames, msg_type="nobody_knows/Opaque"):
        done = run_cli("bag", "record", "-O", str(tmp_path / "o.bag"), "/opaque", "-l", "50",
                       env=cli_env, timeout=60)  # fmt: skip
    assert done.returncode == 0, done.stderr
    with open_bag(tmp_path / "o.bag") as reader:
        (conn,) = reader.connections
        assert (conn.type, conn.definition) == ("nobody_knows/Opaque", BROKEN)
        got = [bytes(d) for _, _, d in reader.messages()]
    assert got == [struct.pack("<I", i) + b"opaque" * 10 for i in range(got[0][0], 50 + got[0][0])]
    # play sends the same bytes, and record takes them again: a round trip, byte for byte
    again = start_cli(
        "bag", "record", "-O", "again.bag", "/opaque", "-l", "50", env=cli_env, cwd=tmp_path
    )
    try:
        play = run_cli("bag", "play", "--wait-for-subscribers", str(tmp_path / "o.bag"),
                       env=cli_env, timeout=60)  # fmt: skip
        assert play.returncode == 0, play.stderr
        assert again.popen.wait(30) == 0
    finally:
        again.stop()
    with open_bag(tmp_path / "again.bag") as reader:
        assert [bytes(d) for _, _, d in reader.messages()] == got


def test_snapshot_never_decodes(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    snap = start_cli("bag", "snapshot", "/opaque", "__name:=snap", env=cli_env, cwd=tmp_path)
    opaque = "nobody_knows/Opaque"
    try:
        with FakePublisher(rostools_master, "/opaque", _broken_frames, msg_type=opaque):
            wait_for(lambda: linked(rostools_master, "/snap", "/opaque"), 20, "/snap on /opaque")
            done = run_cli("bag", "trigger", "/snap", "-O", "o.bag", "--after", "0.5",
                           env=cli_env, timeout=60)  # fmt: skip
    finally:
        snap.stop()
    assert done.returncode == 0, done.stderr
    with open_bag(tmp_path / "o.bag") as reader:
        (conn,) = reader.connections
        assert (conn.type, conn.definition) == ("nobody_knows/Opaque", BROKEN)
        got = [bytes(d) for _, _, d in reader.messages()]
    first = got[0][0]
    assert got == [struct.pack("<I", i) + b"opaque" * 10 for i in range(first, first + len(got))]


@pytest.mark.parametrize(
    ("argv", "reuse", "coalesce"),
    [
        (["topic", "echo", "/chatter", "-n", "1"], False, 0.0),
        (["bag", "record", "/chatter", "-l", "1", "-O", "{tmp}/r.bag"], False, 0.0),
        (["topic", "hz", "/chatter", "--timeout", "1.2"], True, 0.001),
        (["topic", "bw", "/chatter", "--timeout", "1.2"], True, 0.001),
        # log echo keeps no frame past its batch, but a reuse would buy it nothing
        (["log", "echo", "--topic", "/chatter", "--timeout", "1.2"], False, 0.001),
    ],
    ids=["echo", "record", "hz", "bw", "log-echo"],
)
def test_how_each_command_subscribes(
    monkeypatch: pytest.MonkeyPatch,
    tmp_path: Path,
    argv: list[str],
    reuse: bool,
    coalesce: float,
) -> None:
    """Only a callback done with each frame when it returns may ask for ``reuse_frames``
    (record and echo keep frames past the call); the meters gather small reads for 1 ms.

    Run in this process, so that the subscription's options can be seen; a reuse in echo
    corrupts nothing today only because its loop happens to print a batch before the next
    read, and a meter without coalescing only costs CPU.
    """
    import rostools
    from rostools.cli import main
    from rostools.master.server import MasterThread
    from rostools.node.node import LiveNode

    asked: list[dict[str, object]] = []
    subscribe = LiveNode.subscribe

    async def spy(self: LiveNode, topic: str, *args: object, **kwargs: object) -> object:
        if topic == "/chatter":
            asked.append(kwargs)
        return await subscribe(self, topic, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(LiveNode, "subscribe", spy)
    with MasterThread() as master, rostools.Node("talker", master.uri) as node:
        monkeypatch.setenv("ROS_MASTER_URI", master.uri)
        pub = node.advertise("/chatter", "std_msgs/String", latch=True)
        pub.publish(data="hi")
        with pytest.raises(SystemExit) as done:
            main([a.format(tmp=tmp_path) for a in argv])
    assert done.value.code == 0
    assert [(a.get("reuse_frames", False), a.get("coalesce", 0.0)) for a in asked] == [
        (reuse, coalesce)
    ]
