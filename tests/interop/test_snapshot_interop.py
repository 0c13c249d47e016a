"""``bag snapshot`` and ``bag trigger`` with real ROS 1: rospy and roscpp talkers, a rospy client.

Each test runs on ``rostools core`` and on a real ``roscore``. One recorder buffers a rospy and
a roscpp talker and a latched topic published once; a rospy client (its service class built by
genmsg, so the type and md5sum are checked by rospy itself) and ``bag trigger`` ask for
overlapping ``--before 5 --after 5`` windows 1 s apart. A last trigger takes the whole buffer:
every snapshot must hold exactly its window of it, message for message, stamps and all.
"""

from __future__ import annotations

import json
import signal
import time
from pathlib import Path

import pytest

from rostools.bag.formats.access import open_bag
from tests.conftest import MasterInfo
from tests.support import cppbuild
from tests.support.bagdata import recorded
from tests.support.env import needs_ros1, run_cli
from tests.support.procs import Proc, linked, start_cli, start_ros1_node, wait_for

pytestmark = [pytest.mark.interop, needs_ros1]
_CPP_REASON = cppbuild.cpp_missing()
needs_cpp = pytest.mark.skipif(_CPP_REASON is not None, reason=_CPP_REASON or "")

TOPICS = ("/py", "/cpp")
RATE = 20  # Hz of each talker
NS = 1_000_000_000

Message = tuple[str, int, bytes]  # topic, receive time (ns), raw bytes


def messages(path: Path) -> list[Message]:
    with open_bag(path) as reader:
        return sorted((c.topic, t, bytes(d)) for c, t, d in reader.messages())


def numbers(msgs: list[Message], topic: str) -> list[int]:
    return [int(d[4:].decode().split()[1]) for t, _, d in msgs if t == topic]


def check_window(got: list[Message], everything: list[Message], window: list[int]) -> None:
    """``got`` holds exactly what ``everything`` holds in the window, and the latched copy."""
    start, stop = window
    want = [m for m in everything if m[0] in TOPICS and start <= m[1] <= stop]
    assert [m for m in got if m[0] in TOPICS] == want
    for topic in TOPICS:
        count = len(numbers(want, topic))
        assert abs(count - 10 * RATE) <= 0.2 * 10 * RATE, (topic, count)  # the talker's pace
        assert numbers(want, topic) == sorted(numbers(want, topic))
    # published once, long before the window: kept, and stamped at its start
    assert [(t, d[4:]) for topic, t, d in got if topic == "/latched"] == [(start, b"hello 0")]


def written(snap: Proc, name: str) -> dict[str, object]:
    """The recorder's NDJSON record of the file ``name``, once it is complete."""
    line = snap.expect(rf'"event": ?"written".*"name": ?"{name}"', 30)
    record: dict[str, object] = json.loads(line)
    assert record["error"] is None, record
    return record


@needs_cpp
def test_snapshot_windows_of_rospy_and_roscpp_publishers(
    any_master: MasterInfo, tmp_path: Path
) -> None:
    env = any_master.cli_env
    snap = start_cli(
        "bag", "snapshot", *TOPICS, "/latched", "-d", "30", "-F", "json", "__name:=snap",
        env=env, cwd=tmp_path,
    )  # fmt: skip
    talker = cppbuild.build("talker")
    ros = any_master.ros_env
    peers = [
        start_ros1_node(
            "talker.py", ["/latched", "10", "1", "1", "__name:=latcher"], any_master.ros_env
        ),
        start_ros1_node("talker.py", ["/py", str(RATE)], ros),
        Proc([str(talker), "/cpp", "--rate", str(RATE), "--name", "cpp"], env=ros),
    ]
    try:
        for topic in (*TOPICS, "/latched"):
            wait_for(lambda t=topic: linked(any_master.uri, "/snap", t), 30, f"/snap on {topic}")
        linked_at = int(peers[2].expect(r"^sent hello ", 10).split()[2])
        peers[2].expect(rf"^sent hello {linked_at + 6 * RATE}$", 20)  # > --before 5 buffered
        client = start_ros1_node(
            "snapshot_client.py", ["/trigger_snapshot", "5", "5", "a.bag", "../evil.bag"],
            any_master.ros_env,
        )  # fmt: skip
        peers.append(client)
        first = client.expect(r"^answer ", 30).split()
        assert first[1] == "True" and first[4] == "a.bag", first
        refused = client.expect(r"^answer ", 10)
        assert (
            refused.startswith("answer False ") and "refused the file name '../evil.bag'" in refused
        )
        one_later = int(first[2]) + 6 * NS  # the trigger's time + 1 s (the window starts 5 s back)
        wait_for(lambda: time.time_ns() >= one_later, 5, "a second after the first trigger")
        second = run_cli(
            "bag", "trigger", "/snap", "-O", "b.bag", "--before", "5", "--after", "5", "-F",
            "json", env=env, timeout=60,
        )  # fmt: skip
        assert second.returncode == 0, second.stderr
        b = json.loads(second.stdout)
        a = written(snap, "a.bag")
        assert a["window_ns"] == [int(first[2]), int(first[3])]
        whole = run_cli("bag", "trigger", "/snap", "-O", "all.bag", env=env, timeout=60)
        assert whole.stdout.strip() == "all.bag", whole.stderr
        everything = messages(tmp_path / "all.bag")
        check_window(messages(tmp_path / "a.bag"), everything, a["window_ns"])  # type: ignore[arg-type]
        check_window(messages(tmp_path / "b.bag"), everything, b["window_ns"])
        assert b["messages"] == len(messages(tmp_path / "b.bag"))
        killed_while_writing(snap, tmp_path, env)
    finally:
        snap.stop()
        for peer in peers:
            peer.stop()


def killed_while_writing(snap: Proc, folder: Path, env: dict[str, str]) -> None:
    """SIGKILL during a write (its live part) leaves a file that ``bag recover`` restores."""
    started = run_cli(
        "bag", "trigger", "/snap", "-O", "k.bag", "--after", "30", "--timeout", "1", env=env
    )
    assert started.returncode == 5, started.stderr  # gave up waiting; the file is under way
    active = folder / "k.bag.active"
    # once the buffered part and some live messages are on disk, in whole chunks
    wait_for(lambda: all(recorded(active, t) > 2 * RATE for t in TOPICS), 20, "k.bag on disk")
    snap.signal(signal.SIGKILL)
    snap.popen.wait(10)
    done = run_cli("bag", "recover", str(active), env=env)
    assert done.returncode in (0, 6), done.stderr
    got = messages(folder / "k.bag")
    for topic in TOPICS:
        hellos = numbers(got, topic)
        assert len(hellos) > RATE, topic  # everything buffered, and a second live at least
        assert hellos == list(range(hellos[0], hellos[0] + len(hellos))), topic  # none lost


@needs_cpp
def test_a_local_trigger_writes_its_before_and_after_in_seconds(
    any_master: MasterInfo, tmp_path: Path
) -> None:
    """SIGUSR1 (as ``s`` and ``~trigger``): ``--before 2 --after 2`` is four seconds of talk."""
    env = any_master.cli_env
    snap = start_cli(
        "bag", "snapshot", *TOPICS, "--before", "2", "--after", "2", "-F", "json",
        "-O", "local.bag", "__name:=snap", env=env, cwd=tmp_path,
    )  # fmt: skip
    peers = [
        start_ros1_node("talker.py", ["/py", str(RATE)], any_master.ros_env),
        Proc([str(cppbuild.build("talker")), "/cpp", "--rate", str(RATE), "--name", "cpp"],
             env=any_master.ros_env),
    ]  # fmt: skip
    try:
        for topic in TOPICS:
            wait_for(lambda t=topic: linked(any_master.uri, "/snap", t), 30, f"/snap on {topic}")
        linked_at = int(peers[1].expect(r"^sent hello ", 10).split()[2])
        peers[1].expect(rf"^sent hello {linked_at + 4 * RATE}$", 20)  # > --before buffered
        snap.signal(signal.SIGUSR1)
        record = written(snap, "local.bag")
        start, stop = record["window_ns"]  # type: ignore[misc]
        assert stop - start == 4 * NS, record  # seconds, both sides of the trigger
        got = messages(tmp_path / "local.bag")
        for topic in TOPICS:
            hellos = numbers(got, topic)
            assert abs(len(hellos) - 4 * RATE) <= 0.2 * 4 * RATE, (topic, len(hellos))
            assert all(start <= t <= stop for top, t, _ in got if top == topic)
        assert record["lost"] == 0, record
    finally:
        snap.stop()
        for peer in peers:
            peer.stop()


def test_a_window_older_than_the_buffer_says_how_many_it_lost(
    any_master: MasterInfo, tmp_path: Path
) -> None:
    """rospy 1 MB images into a 3 MB buffer: ``--before 600`` lost what the size evicted.

    Each loss is counted exactly, in bag trigger's JSON and text and its exit 6, and in the
    recorder's line and exit 6; the latched message the size evicted is no loss: it is written.
    """
    env = any_master.cli_env
    snap = start_cli(
        "bag", "snapshot", "/image", "/latched", "--size", "3", "-F", "json", "__name:=snap",
        env=env, cwd=tmp_path,
    )  # fmt: skip
    latcher = start_ros1_node(
        "talker.py", ["/latched", "10", "1", "1", "__name:=latcher"], any_master.ros_env
    )
    images = start_ros1_node("image_pub.py", [], any_master.ros_env)
    try:
        for topic in ("/image", "/latched"):
            wait_for(lambda t=topic: linked(any_master.uri, "/snap", t), 30, f"/snap on {topic}")
        for _ in range(12):  # the buffer holds two: the rest go, and the latched one
            images.expect(r"^sent ", 20)
        images.stop()
        wait_for(lambda: not linked(any_master.uri, "/snap", "/image"), 20, "the images' end")
        done = run_cli(
            "bag", "trigger", "/snap", "-O", "old.bag", "--before", "600", "-F", "json",
            env=env, timeout=60,
        )  # fmt: skip
        assert done.returncode == 6, done.stderr
        summary = json.loads(done.stdout)
        kept = messages(tmp_path / "old.bag")
        assert [d[4:] for t, _, d in kept if t == "/latched"] == [b"hello 0"]
        text = run_cli(
            "bag", "trigger", "/snap", "-O", "old2.bag", "--before", "600", env=env, timeout=60
        )
        assert text.returncode == 6 and text.stdout.strip() == "old2.bag", text.stderr
        snap.signal(signal.SIGINT)
        assert snap.popen.wait(30) == 6
        stopped = json.loads(snap.expect(r'"event": ?"stopped"', 10))
        image_topic = stopped["topics"]["/image"]
        received = image_topic["received"]
        in_file = len([m for m in kept if m[0] == "/image"])
        assert received - in_file >= 1  # (images sent before the link never came)
        assert summary["evicted"] == received - in_file == summary["lost"]
        assert summary["lost_exact"] is True and summary["drops"] == 0
        line = f"old2.bag: {summary['lost']} messages of the window LOST ({summary['lost']} let go"
        assert line in text.stderr, text.stderr
        err = snap.output()[1]
        assert f"2 snapshots not written whole: old.bag ({summary['lost']} lost)" in err, err
    finally:
        snap.stop()
        images.stop()
        latcher.stop()
