"""``rostools bag record`` and ``bag play`` end to end on the bundled master."""

from __future__ import annotations

import itertools
import json
import re
import signal
import struct
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from rostools.bag.formats.access import bag_info, detect_format, open_bag
from tests.support.bagdata import recorded, write_play_bag, write_static_bag
from tests.support.env import needs_ros1, run_cli
from tests.support.load import scaled
from tests.support.procs import (
    Proc,
    linked,
    publishers,
    start_cli,
    subscribed,
    wait_for,
    wait_for_name,
)

_STARTED: list[Proc] = []


@pytest.fixture(autouse=True)
def _stop_everything_started() -> Iterator[None]:
    """Whatever a test started here is stopped after it, even when an assertion failed."""
    yield
    while _STARTED:
        _STARTED.pop().stop()


def rostools(env: dict[str, str], *args: str, cwd: Path | None = None) -> Proc:
    """``rostools ARGS``, stopped after the test."""
    proc = start_cli(*args, env=env, cwd=cwd)
    _STARTED.append(proc)
    return proc


def seqs(path: Path, topic: str) -> list[int]:
    """The header.seq of every message on ``topic`` (stamped messages)."""
    with open_bag(path) as reader:
        return [struct.unpack_from("<I", data)[0] for c, _, data in reader.messages([topic])]


def strings(path: Path, topic: str) -> list[str]:
    with open_bag(path) as reader:
        return [bytes(data[4:]).decode() for _, _, data in reader.messages([topic])]


def start_publishers(env: dict[str, str]) -> list[Proc]:
    return [
        rostools(env, "topic", "pub", "-r", "100", "/h", "geometry_msgs/PointStamped", "{}"),
        rostools(env, "topic", "pub", "-l", "/latched", "std_msgs/String", "data: kept"),
    ]


def stop_all(procs: list[Proc]) -> None:
    for proc in procs:
        proc.stop()


def wait_recorded(path: Path, topic: str, count: int, timeout: float = 20) -> None:
    """Until the recording ``path`` holds ``count`` messages on ``topic`` on disk."""
    wait_for(lambda: recorded(path, topic) >= count, timeout, f"{count} on {topic} in {path}", 0.2)


def test_record_closes_on_sigint_and_keeps_everything(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    pubs = start_publishers(cli_env)
    rec = rostools(
        cli_env, "bag", "record", "-O", "run", "/h", "/latched", "-F", "json", cwd=tmp_path
    )
    try:
        wait_for(
            lambda: subscribed(rostools_master, "/h", "/rostools_record"), 15, "record to subscribe"
        )
        wait_recorded(tmp_path / "run.bag.active", "/h", 51)
        rec.signal(signal.SIGINT)
        out, err = rec.output()
        assert rec.popen.returncode == 0, err
    finally:
        stop_all(pubs)
    assert "Recording to 'run.bag'." in err
    assert not (tmp_path / "run.bag.active").exists()
    summary = json.loads(out)
    assert summary["files"] == ["run.bag"]
    assert summary["drops"] == 0
    got = seqs(tmp_path / "run.bag", "/h")
    assert len(got) == summary["topics"]["/h"]["messages"] > 50
    assert got == list(range(got[0], got[0] + len(got)))  # nothing lost between first and last
    assert strings(tmp_path / "run.bag", "/latched") == ["kept"]
    with open_bag(tmp_path / "run.bag") as reader:
        latched = [c for c in reader.connections if c.topic == "/latched"]
        assert [c.latching for c in latched] == [True]
        assert latched[0].callerid.startswith("/rostools_pub")
    assert bag_info(tmp_path / "run.bag").indexed


def test_record_names_like_rosbag(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    pubs = start_publishers(cli_env)
    try:
        for args in (["-o", "pre"], ["-O", "named.mcap"], ["-O", "fmt", "--storage", "mcap"], []):
            done = run_cli("bag", "record", "/latched", "-l", "1", *args, env=cli_env, cwd=tmp_path)
            assert done.returncode == 0, done.stderr
    finally:
        stop_all(pubs)
    names = sorted(p.name for p in tmp_path.iterdir())
    stamp = r"\d{4}(-\d\d){5}"
    assert [n for n in names if re.fullmatch(f"pre_{stamp}\\.bag", n)]
    assert [n for n in names if re.fullmatch(f"{stamp}\\.bag", n)]
    assert {"named.mcap", "fmt.mcap"} <= set(names)
    assert detect_format(tmp_path / "fmt.mcap") == "mcap"
    assert strings(tmp_path / "named.mcap", "/latched") == ["kept"]


@pytest.mark.parametrize("storage", ["bag", "mcap"])
def test_record_splits_keeps_newest_and_repeats_latched(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path, storage: str
) -> None:
    pubs = start_publishers(cli_env)
    rec = rostools(
        cli_env, "bag", "record", "-O", f"s.{storage}", "--split", "--duration", "1",
        "--max-splits", "2", "--repeat-latched", "/h", "/latched", cwd=tmp_path,
    )  # fmt: skip
    try:
        wait_for(lambda: (tmp_path / f"s_3.{storage}.active").exists(), 20, "four splits")
        assert rec.stop() == 0
    finally:
        stop_all(pubs)
    files = sorted(tmp_path.glob(f"s_*.{storage}"), key=lambda p: int(p.stem[2:]))
    # the two newest closed splits and the last one, as rosbag keeps N + 1 (it kept 2)
    assert len(files) == 3, files
    assert not list(tmp_path.glob("*.active"))
    for path in files:
        assert strings(path, "/latched") == ["kept"]
        with open_bag(path) as reader:
            assert [c.latching for c in reader.connections if c.topic == "/latched"] == [True]
        info = bag_info(path)
        assert info.duration_ns < 1.5e9
    for first, second in itertools.pairwise(files):
        assert seqs(second, "/h")[0] == seqs(first, "/h")[-1] + 1  # a split loses nothing


@needs_ros1
@pytest.mark.interop
def test_record_max_splits_keeps_as_many_files_as_rosbag(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    pubs = start_publishers(cli_env)
    flags = ["--split", "--duration", "1", "--max-splits", "2", "/h"]
    ros_env = dict(cli_env, ROS_HOME=str(tmp_path))
    ours = rostools(cli_env, "bag", "record", "-O", "ours.bag", *flags, cwd=tmp_path)
    theirs = Proc(["rosbag", "record", "-O", "theirs.bag", *flags], env=ros_env, cwd=tmp_path)
    try:
        wait_for(
            lambda: (
                (tmp_path / "ours_4.bag.active").exists()
                and (tmp_path / "theirs_4.bag.active").exists()
            ),
            30,
            "five splits of each",
        )
    finally:
        theirs.stop()
        ours.stop()
        stop_all(pubs)
    mine = sorted(p.name for p in tmp_path.glob("ours_*.bag"))
    rosbags = sorted(p.name for p in tmp_path.glob("theirs_*.bag"))
    assert len(mine) == len(rosbags) == 3, (mine, rosbags)


def test_record_limit_duration_regex_and_late_topics(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    pubs = start_publishers(cli_env)
    try:
        done = run_cli(
            "bag", "record", "-q", "-O", str(tmp_path / "l.bag"), "-l", "5", "/h", env=cli_env
        )
        assert done.returncode == 0 and done.stderr == "", done.stderr  # -q: no summary either
        assert len(seqs(tmp_path / "l.bag", "/h")) == 5
        done = run_cli(
            "bag", "record", "-O", str(tmp_path / "d.bag"), "--duration", "1", "/h", env=cli_env
        )
        assert done.returncode == 0, done.stderr  # it ended by itself (run_cli's timeout)
        # about a second of the 100 Hz stream, however long starting took on a busy machine
        assert 0 < len(seqs(tmp_path / "d.bag", "/h")) < 150
        assert bag_info(tmp_path / "d.bag").duration_ns < 1.5e9
        rec = rostools(
            cli_env, "bag", "record", "-O", str(tmp_path / "e.bag"), "-e", "/a/.*", "-x", "/a/y",
            "-x", "/a/z.*",  # several excludes: any one leaves a topic out
        )  # fmt: skip
        # The topics left out come first: the master poll that finds /a/x finds them too.
        late = [
            rostools(cli_env, "topic", "pub", "-r", "20", name, "std_msgs/String", "data: x")
            for name in ("/a/y", "/a/zz", "/a", "/b/a/x")
        ]
        try:
            for topic in ("/a/y", "/a/zz", "/a", "/b/a/x"):
                wait_for(lambda t=topic: publishers(rostools_master, t), 15, f"{topic} published")
            late.append(
                rostools(cli_env, "topic", "pub", "-r", "20", "/a/x", "std_msgs/String", "data: x")
            )
            wait_recorded(tmp_path / "e.bag.active", "/a/x", 1)
            assert rec.stop() == 0
        finally:
            stop_all(late)
    finally:
        stop_all(pubs)
    assert {t.topic for t in bag_info(tmp_path / "e.bag").topics} == {"/a/x"}


@pytest.mark.parametrize("storage", ["bag", "mcap"])
def test_sigkilled_recording_is_recovered(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path, storage: str
) -> None:
    pubs = start_publishers(cli_env)
    active = tmp_path / f"k.{storage}.active"
    rec = rostools(cli_env, "bag", "record", "-O", f"k.{storage}", "/h", "/latched", cwd=tmp_path)
    try:
        wait_recorded(active, "/h", 101)
        rec.signal(signal.SIGKILL)
        rec.stop()
    finally:
        stop_all(pubs)
    with open_bag(active) as reader:
        on_disk = [(c.topic, t, bytes(d)) for c, t, d in reader.messages()]
    done = run_cli("bag", "recover", str(active), "-F", "json", env=cli_env)
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout)
    out = tmp_path / f"k.{storage}"
    assert report["output"] == str(out) and report["lost"] == []
    with open_bag(out) as reader:
        recovered = [(c.topic, t, bytes(d)) for c, t, d in reader.messages()]
    assert recovered == on_disk
    got = seqs(out, "/h")
    assert len(got) > 100 and got == list(range(got[0], got[0] + len(got)))
    assert bag_info(out).indexed


def echo(env: dict[str, str], topic: str, count: int) -> Proc:
    return rostools(env, "topic", "echo", topic, "-n", str(count), "-F", "json")


def received(proc: Proc) -> list[str]:
    assert proc.popen.wait(30) == 0
    out, _ = proc.output()
    return [json.loads(line)["data"] for line in out.splitlines()]


def test_play_paces_remaps_and_prefixes(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    bag = tmp_path / "p.bag"
    write_play_bag(bag)
    # echo subscribes once the topic exists: the 3 s delay after advertising lets it
    player = rostools(cli_env, "bag", "play", str(bag), "-d", "3", "-p", "/r", "/r/latched:=/moved")
    listeners = [echo(cli_env, "/r/chatter", 10), echo(cli_env, "/moved", 1)]
    started = time.monotonic()
    assert player.popen.wait(30) == 0
    took = time.monotonic() - started
    assert received(listeners[0]) == [f"m{i}" for i in range(10)]
    assert received(listeners[1]) == ["old"]
    assert took > 0.9  # 0.9 s of bag time
    started = time.monotonic()
    done = run_cli("bag", "play", str(bag), "-r", "10", "-d", "0", env=cli_env)
    assert done.returncode == 0 and time.monotonic() - started < took


def test_play_start_still_delivers_latched_and_keep_alive(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    bag = tmp_path / "p.bag"
    write_play_bag(bag)
    player = rostools(cli_env, "bag", "play", str(bag), "-s", "0.5", "-d", "3", "-k")
    try:
        chatter = echo(cli_env, "/chatter", 5)
        assert received(chatter) == [f"m{i}" for i in range(5, 10)]
        late = echo(cli_env, "/latched", 1)  # "old" was before -s: sent anyway, and kept
        assert received(late) == ["old"]
        assert player.popen.poll() is None  # -k: still up after the end
    finally:
        assert player.stop() == 0


def test_play_latches_the_last_message_of_every_recorded_publisher(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    bag = tmp_path / "static.bag"
    write_static_bag(bag)
    player = rostools(cli_env, "bag", "play", str(bag), "-d", "0", "-k", "--wait-for-subscribers")
    try:
        assert received(echo(cli_env, "/static", 4)) == ["a1", "b1", "c1", "a2"]  # all played
        late = rostools(cli_env, "topic", "echo", "/static", "-n", "3", "--timeout", "3", "-F",
                        "json")  # fmt: skip
        assert late.popen.wait(30) == 5  # only two come: c1 was not latched, a1 was replaced
        out, _ = late.output()
        assert [json.loads(line)["data"] for line in out.splitlines()] == ["b1", "a2"]
    finally:
        assert player.stop() == 0


def test_play_topics_clock_and_immediate(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    bag = tmp_path / "p.mcap"
    write_play_bag(bag)
    player = rostools(
        cli_env, "bag", "play", str(bag), "--clock", "--topics", "/chatter", "-d", "3", "-k"
    )
    try:
        clock = rostools(cli_env, "topic", "echo", "/clock", "-n", "3", "-F", "json")
        assert clock.popen.wait(30) == 0
        stamps = [json.loads(line)["clock"]["secs"] for line in clock.output()[0].splitlines()]
        assert len(stamps) == 3 and all(100 <= s <= 101 for s in stamps)
        listed = run_cli("topic", "list", env=cli_env).stdout.split()
        assert "/chatter" in listed and "/latched" not in listed
    finally:
        player.stop()
    done = run_cli("bag", "play", str(bag), "-i", "-d", "0", "-F", "json", env=cli_env)
    assert done.returncode == 0 and json.loads(done.stdout) == {"published": 11}


@pytest.mark.parametrize("command", ["play", "info", "recover"])
def test_bad_files_are_one_line_errors(
    cli_env: dict[str, str], tmp_path: Path, command: str
) -> None:
    (tmp_path / "empty.bag").write_bytes(b"")
    (tmp_path / "text.bag").write_text("hello\n")
    (tmp_path / "db.bag").write_bytes(b"SQLite format 3\x00" + bytes(100))
    cases = {"missing.bag": 3, "empty.bag": 1, "text.bag": 1, "db.bag": 1}
    for name, code in cases.items():
        done = run_cli("bag", command, str(tmp_path / name), env=cli_env)
        assert done.returncode == code, (name, done.stderr)
        assert done.stderr.count("\n") == 1 and "Traceback" not in done.stderr, done.stderr
        assert name in done.stderr


def test_record_usage_errors(cli_env: dict[str, str], tmp_path: Path) -> None:
    for args, words in (
        ([], "give topics"),
        (["-a", "/x"], "do not also name"),
        (["/x", "--split"], "--split needs"),
        (["/x", "-O", "a", "-o", "b"], "cannot be combined"),
        (["/x", "--duration", "soon"], "bad duration"),
        (["/x", "--storage", "mcap", "--bz2"], "cannot use bz2"),
        (["/x", "-O", str(tmp_path / "nowhere" / "x.bag")], "no such folder"),
        (["-a", "-l", "3"], "-l"),
        (["/x", "-L", "lots"], "bad size 'lots' for -L"),
        (["-x", "/y"], "-x subtracts from -a or -e"),  # rosbag: "must specify a topic name"
    ):
        done = run_cli("bag", "record", *args, env=cli_env)
        assert done.returncode == 2, (args, done.stderr)
        assert words in done.stderr and done.stderr.count("\n") == 1, done.stderr


def test_record_refuses_a_disk_below_min_space(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    done = run_cli("bag", "record", "-L", "1000000G", "/x", env=cli_env, cwd=tmp_path)
    assert done.returncode == 1, done.stderr
    assert done.stderr.startswith("rostools: less than 1000000G free on the disk of ")
    assert ": not recording (hint: free some space" in done.stderr
    assert done.stderr.count("\n") == 1
    assert list(tmp_path.iterdir()) == []


def test_record_publish_announces_every_file(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    pubs = start_publishers(cli_env)
    rec = rostools(
        cli_env, "bag", "record", "-p", "-O", "a.bag", "--split", "--duration", "1", "/h",
        cwd=tmp_path,
    )  # fmt: skip
    try:
        # latched: a late subscriber still hears of the file being written
        wait_for(lambda: (tmp_path / "a_1.bag.active").exists(), 20, "the second file")
        # the file being written when the echo starts: a_1 or, on a slow machine, a later one
        (name,) = received(echo(cli_env, "/begin_write", 1))
        assert re.fullmatch(r"a_([1-9]\d*)\.bag", name), name
        topic_type = run_cli("topic", "type", "/begin_write", env=cli_env).stdout
        assert topic_type == "std_msgs/String\n"
        assert rec.stop() == 0
    finally:
        stop_all(pubs)


def test_record_without_master_is_unreachable(cli_env: dict[str, str], tmp_path: Path) -> None:
    done = run_cli("bag", "record", "-O", str(tmp_path / "x.bag"), "/x", env=cli_env)
    assert done.returncode == 4, done.stderr
    assert done.stderr.splitlines()[-1].startswith("rostools: cannot reach the master")
    assert list(tmp_path.iterdir()) == []


def test_play_keys_step_and_pause(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    import pexpect

    bag = tmp_path / "p.bag"
    write_play_bag(bag)
    argv = ["-m", "rostools", "bag", "play", str(bag), "--pause", "-d", "0"]
    child = pexpect.spawn(sys.executable, argv, env=cli_env, timeout=20, encoding="utf-8")
    try:
        child.expect("Hit space to toggle paused, or 's' to step.")
        child.expect(r"\[PAUSED \]")
        chatter = echo(cli_env, "/chatter", 3)
        wait_for(
            lambda: any(
                peer.startswith("/rostools_echo")
                for player in publishers(rostools_master, "/chatter")
                for peer in linked(rostools_master, player, "/chatter")
            ),
            15,
            "the player connected to echo",
        )
        child.send("ssss")  # /latched "old", then m0, m1, m2
        assert received(chatter) == ["m0", "m1", "m2"]
        child.expect(r"\[PAUSED \]")  # still paused after the steps
        child.send(" ")
        child.expect("Done.")
        child.expect(pexpect.EOF)
    finally:
        child.close(force=True)
    assert child.exitstatus == 0


def test_play_of_dense_messages_serves_late_subscribers_and_ctrl_c(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    from rostools.bag.formats.access import open_writer
    from tests.support.bagdata import STRING_MD5

    bag = tmp_path / "dense.bag"
    with open_writer(bag) as writer:  # 60 s of messages 1 ms apart
        conn = writer.add_connection("/dense", "std_msgs/String", STRING_MD5, "string data\n")
        for i in range(60_000):
            writer.write(conn, 10**9 + i * 10**6, struct.pack("<I", 1) + b"x")
    player = rostools(cli_env, "bag", "play", str(bag), "-d", "0")
    try:
        late = echo(cli_env, "/dense", 10)  # subscribes while playback runs back to back
        assert received(late) == ["x"] * 10
        player.signal(signal.SIGINT)
        started = time.monotonic()
        assert player.popen.wait(60) == 0
        assert time.monotonic() - started < min(scaled(1.0), 30)  # not at the bag's end
    finally:
        player.stop()


def pause_service(env: dict[str, str]) -> str:
    """The name of the player's ``~pause_playback`` service, once it is registered."""
    return wait_for_name(
        lambda: run_cli("service", "list", env=env).stdout.split(), "/pause_playback"
    )


def set_paused(env: dict[str, str], service: str, paused: bool) -> dict[str, object]:
    done = run_cli("service", "call", service, "true" if paused else "false", "-F", "json", env=env)
    assert done.returncode == 0, done.stderr
    reply: dict[str, object] = json.loads(done.stdout)
    return reply


def test_play_pause_topics_and_pause_service(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    bag = tmp_path / "p.bag"
    write_play_bag(bag)
    player = rostools(
        cli_env, "bag", "play", str(bag), "--topics", "/chatter", "--pause-topics", "/chatter",
        "--wait-for-subscribers", "-d", "0",
    )  # fmt: skip
    chatter = rostools(cli_env, "topic", "echo", "/chatter", "-F", "json")
    service = pause_service(cli_env)
    already = {"success": False, "message": "Bag is already paused."}
    # Paused with m0 next: by --pause-topics, or by this call if it came first.
    wait_for(lambda: set_paused(cli_env, service, True) == already, 15, "the pause before m0")
    for i in range(3):  # a resume sends the pending message and pauses before the next
        reply = set_paused(cli_env, service, False)
        assert reply == {"success": True, "message": "Playback is now resumed"}
        assert json.loads(chatter.expect(r'"data"'))["data"] == f"m{i}"
        wait_for(lambda: set_paused(cli_env, service, True) == already, 15, "the next pause")
    with pytest.raises(AssertionError, match="printed no line"):
        chatter.expect(r'"data"', timeout=1.0)  # m3 stays pending while paused
    assert player.popen.poll() is None


def test_play_waits_for_the_rate_control_topic(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    bag = tmp_path / "p.bag"
    write_play_bag(bag)  # /chatter m0..m9 at 100.0, 100.1, ... 100.9 s
    player = rostools(
        cli_env, "bag", "play", str(bag), "--topics", "/chatter", "--wait-for-subscribers",
        "-d", "0", "--rate-control-topic", "/ctl", "--rate-control-max-delay", "0.25",
    )  # fmt: skip
    chatter = rostools(cli_env, "topic", "echo", "/chatter", "-F", "json")

    def played(count: int) -> list[str]:
        return [json.loads(chatter.expect(r'"data"'))["data"] for _ in range(count)]

    # No stamp yet: bag time may run 0.25 s past the start, so m0..m2 go and m3 waits.
    assert played(3) == ["m0", "m1", "m2"]
    with pytest.raises(AssertionError, match="printed no line"):
        chatter.expect(r'"data"', timeout=1.5)
    stamp = "{header: {stamp: {secs: 100, nsecs: 500000000}}}"
    ctl = run_cli("topic", "pub", "-1", "/ctl", "geometry_msgs/PointStamped", stamp, env=cli_env)
    assert ctl.returncode == 0, ctl.stderr
    assert played(5) == ["m3", "m4", "m5", "m6", "m7"]  # up to 100.75 s
    with pytest.raises(AssertionError, match="printed no line"):
        chatter.expect(r'"data"', timeout=1.5)
    assert player.popen.poll() is None


def test_record_stamps_with_sim_time(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    assert run_cli("param", "set", "/use_sim_time", "true", env=cli_env).returncode == 0
    rec = rostools(cli_env, "bag", "record", "-O", "sim.bag", "/chatter", "/clock", cwd=tmp_path)
    rec.expect("no clock is published; still waiting", 20, stderr=True)  # after 2 s
    assert list(tmp_path.iterdir()) == []  # nothing is recorded, not even a file
    bag = tmp_path / "p.bag"
    write_play_bag(bag)  # bag time 100.0 .. 100.9 s
    player = rostools(cli_env, "bag", "play", str(bag), "--clock", "-l", "-d", "0.5")
    try:
        wait_recorded(tmp_path / "sim.bag.active", "/chatter", 10)  # a loop of the bag or more
        rec.signal(signal.SIGINT)
        assert rec.popen.wait(20) == 0
    finally:
        player.stop()
    assert "no clock is published; still waiting" in rec.output()[1]
    with open_bag(tmp_path / "sim.bag") as reader:
        times = {c.topic: [] for c in reader.connections}
        for conn, t, _ in reader.messages():
            times[conn.topic].append(t)
    assert set(times) == {"/chatter", "/clock"}  # /clock is recorded as well as followed
    assert len(times["/chatter"]) >= 10
    for stamps in times.values():
        assert stamps and all(100 * 10**9 <= t <= 101 * 10**9 for t in stamps), stamps


def test_play_t_key_turns_pause_topics_off(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    import pexpect

    bag = tmp_path / "p.bag"
    write_play_bag(bag)
    argv = ["-m", "rostools", "bag", "play", str(bag), "--pause-topics", "/chatter", "-d", "0"]
    child = pexpect.spawn(sys.executable, argv, env=cli_env, timeout=20, encoding="utf-8")
    try:
        child.expect("Hit 't' to toggle pausing on --pause-topics.")
        child.expect(r"\[PAUSED \]")  # before m0
        child.send("t")  # no more pauses on /chatter
        child.send(" ")
        child.expect("Done.")  # all ten played: it would stop again before m1 otherwise
        child.expect(pexpect.EOF)
    finally:
        child.close(force=True)
    assert child.exitstatus == 0


def test_play_takes_rosbags_greedy_topics_and_bags(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    bag = tmp_path / "p.bag"
    write_play_bag(bag)  # 10 on /chatter, 1 on /latched
    for args, published in (
        ([str(bag), "--topics", "/latched"], 1),
        ([str(bag), "--topics", "/latched", "/chatter"], 11),  # /chatter: not a file, a topic
        (["--topics", "/latched", "--bags", str(bag)], 1),
        (["--topics", "/chatter", "/latched", "--bags", str(bag)], 11),
    ):
        done = run_cli("bag", "play", *args, "-i", "-d", "0", "-F", "json", env=cli_env)
        assert done.returncode == 0, (args, done.stderr)
        assert json.loads(done.stdout) == {"published": published}, args
    missing = run_cli("bag", "play", "--bags", str(tmp_path / "gone.bag"), env=cli_env)
    assert missing.returncode == 3 and "gone.bag" in missing.stderr
    none = run_cli("bag", "play", "--topics", "/chatter", env=cli_env)
    assert none.returncode == 2 and "give at least one bag" in none.stderr


def test_record_chooses_topics_by_type(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    # /s, left out, comes first: every master poll of the recorders finds it.
    pubs = [rostools(cli_env, "topic", "pub", "-r", "20", "/s", "std_msgs/String", "{}")]
    wait_for(lambda: publishers(rostools_master, "/s"), 15, "/s published")
    pubs += [
        rostools(cli_env, "topic", "pub", "-r", "20", topic, topic_type, "{}")
        for topic, topic_type in (
            ("/img", "sensor_msgs/Image"),
            ("/p", "geometry_msgs/PointStamped"),
        )
    ]
    by_type = rostools(
        cli_env, "bag", "record", "-O", "t.bag", "--topic-types", "sensor_msgs/*",
        "--topic-types", "geometry_msgs/PointStamped", cwd=tmp_path,
    )  # fmt: skip
    but_type = rostools(
        cli_env, "bag", "record", "-O", "x.bag", "-a", "--exclude-topic-types", "std_msgs/*",
        cwd=tmp_path,
    )  # fmt: skip
    try:
        for name in ("t.bag", "x.bag"):
            for topic in ("/img", "/p"):
                wait_recorded(tmp_path / f"{name}.active", topic, 1)
        for rec in (by_type, but_type):
            assert rec.stop() == 0
    finally:
        stop_all(pubs)
    assert {t.topic for t in bag_info(tmp_path / "t.bag").topics} == {"/img", "/p"}
    rest = {t.topic for t in bag_info(tmp_path / "x.bag").topics}
    assert {"/img", "/p"} <= rest and "/s" not in rest
