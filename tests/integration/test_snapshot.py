"""``bag snapshot`` on the bundled master: its services, a trigger storm, a write that fails."""

from __future__ import annotations

import asyncio
import contextlib
import signal
import struct
import sys
from collections.abc import AsyncIterator
from pathlib import Path

import pytest

from rostools.bag.formats.access import open_bag
from rostools.bag.live.snapshot import SnapshotOptions, Snapshotter
from rostools.bag.live.snapshot_client import call
from rostools.bag.live.snapshot_srv import SnapshotRequest, TriggerError
from rostools.master.server import MasterThread
from rostools.msgs.topictype import TopicType
from rostools.msgs.wellknown import TRIGGER
from rostools.node.node import LiveNode
from rostools.node.publisher import TopicPublisher
from tests.support.env import run_cli
from tests.support.procs import Proc, linked, start_cli, wait_for

STRING = TopicType("std_msgs/String", "992ce8a1687cec8c8bd883ec73ca41d1", "string data\n")
NS = 1_000_000_000


def send(pub: TopicPublisher, text: str) -> None:
    data = text.encode()
    pub.publish_raw(struct.pack("<I", len(data)) + data)


async def until(predicate: object, timeout: float = 10.0) -> None:
    """Wait on the loop until ``predicate()`` holds."""
    deadline = asyncio.get_running_loop().time() + timeout
    while not predicate():  # type: ignore[operator]
        assert asyncio.get_running_loop().time() < deadline, "timed out"
        await asyncio.sleep(0.01)


@contextlib.asynccontextmanager
async def graph(tmp_path: Path) -> AsyncIterator[tuple[Snapshotter, TopicPublisher]]:
    """A snapshot recorder of ``/t`` (``--max-writes 1``) and a publisher of it."""
    with MasterThread() as master:
        pub_node = await LiveNode("pub", master.uri).start()
        snap_node = await LiveNode("snap", master.uri).start()
        opts = SnapshotOptions(
            topics=["/t"], base=tmp_path / "s.bag", name="s.bag", max_writes=1, min_space=0
        )
        snap = Snapshotter(snap_node, opts)
        stop = asyncio.Event()
        task = asyncio.ensure_future(snap.run(stop))
        pub = await pub_node.advertise("/t", STRING)
        try:
            await until(lambda: pub.subscriber_count and snap.announce)
            yield snap, pub
        finally:
            stop.set()
            await task
            await snap_node.close()
            await pub_node.close()


def test_the_recorder_is_ready_once_every_service_is_registered(tmp_path: Path) -> None:
    """``announce`` (what ``graph``, and the API's readiness, wait on) comes after the services.

    A master slow to register them (as under load) made ``/snap/pause`` unknown to the test.
    """

    async def main() -> None:
        with MasterThread() as master:
            node = await LiveNode("snap", master.uri).start()
            registered: list[str] = []
            call = node.master.call

            async def slow(method: str, *args: str, timeout: float | None = None) -> object:
                if method != "registerService":
                    return await call(method, *args, timeout=timeout)
                await asyncio.sleep(0.2)  # a loaded master; readiness must not depend on it
                answer = await call(method, *args, timeout=timeout)
                registered.append(args[0])
                return answer

            node.master.call = slow  # type: ignore[method-assign]
            opts = SnapshotOptions(topics=["/t"], base=tmp_path / "s.bag", min_space=0)
            snap = Snapshotter(node, opts)
            stop = asyncio.Event()
            task = asyncio.ensure_future(snap.run(stop))
            try:
                await until(lambda: snap.announce)
                assert set(registered) >= {"/snap/pause", "/snap/stop", "/trigger_snapshot"}
            finally:
                stop.set()
                await task
                await node.close()

    asyncio.run(main())


def test_services_pause_resume_and_end_an_open_ended_file(tmp_path: Path) -> None:
    async def main() -> None:
        async with graph(tmp_path) as (snap, pub):
            await services_steer(snap, pub)

    asyncio.run(main())


async def services_steer(snap: Snapshotter, pub: TopicPublisher) -> None:
    node = snap.node
    send(pub, "before")
    await until(lambda: snap.ring.topics["/t"].entries)
    assert await call(node, "/snap/pause", TRIGGER, b"") == "buffering paused"
    send(pub, "while paused")
    await until(lambda: snap.stats["/t"].messages == 2)
    assert await call(node, "/snap/resume", TRIGGER, b"") == "buffering resumed"
    forever = SnapshotRequest(stop_ns=(2**32 - 1) * NS)
    job = snap.trigger(forever)  # --continue: live until ~stop
    # the storm: one file at a time here (--max-writes 1), the rest refused with the reason
    with pytest.raises(TriggerError, match=r"1 snapshots are being written.*--max-writes 1"):
        snap.trigger(SnapshotRequest())
    send(pub, "live")
    await until(lambda: job.file is not None and job.file.messages == 2)
    assert await call(node, "/snap/stop", TRIGGER, b"") == "1 open-ended snapshot(s) ended"
    await until(lambda: not snap.jobs)
    with open_bag(job.path) as reader:
        assert [bytes(d[4:]) for _, _, d in reader.messages()] == [b"before", b"live"]
    named = await call(node, "/snap/trigger", TRIGGER, b"")  # std_srvs/Trigger: the buffer
    assert named == str(job.path.with_name("s_1.bag"))


def test_a_failed_write_is_one_line_and_buffering_goes_on(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    """A file-size limit (as a full disk) fails one snapshot; the next is written."""
    limit = 512 * 1024
    pub = start_cli(
        "topic", "pub", "-r", "200", "/t", "std_msgs/String", "data: " + "x" * 20_000,
        env=cli_env,
    )  # fmt: skip
    # Python ignores SIGXFSZ, so a write past the limit fails with EFBIG instead of killing it.
    launcher = (
        "import os, resource, sys;"
        f"resource.setrlimit(resource.RLIMIT_FSIZE, ({limit}, {limit}));"
        "os.execv(sys.executable, [sys.executable, '-m', 'rostools', *sys.argv[1:]])"
    )
    snap = Proc(
        [sys.executable, "-c", launcher, "bag", "snapshot", "/t", "-L", "0", "-q", "-d", "5",
         "__name:=snap"], env=cli_env, cwd=tmp_path,
    )  # fmt: skip
    try:
        wait_for(lambda: linked(rostools_master, "/snap", "/t"), 20, "/snap on /t")
        big: list[int] = []

        def failed() -> bool:  # the buffer grows past the limit within a second
            name = f"big{len(big)}.bag"
            done = run_cli("bag", "trigger", "/snap", "-O", name, env=cli_env)
            big.append(done.returncode)
            return done.returncode == 6 and "size limit" in done.stderr

        wait_for(failed, 20, "a snapshot past the size limit")
        small = run_cli("bag", "trigger", "/snap", "-O", "small.bag", "--before", "0.02",
                        env=cli_env)  # fmt: skip
        assert small.returncode == 0, small.stderr
        with open_bag(tmp_path / "small.bag") as reader:
            assert reader.info().message_count >= 1
        snap.signal(signal.SIGINT)
        assert snap.popen.wait(20) == 6
        err = snap.output()[1]
        assert "Traceback" not in err, err
        (line,) = [line for line in err.splitlines() if "cannot write" in line]  # one line
        failure = f"rostools: cannot write big{len(big) - 1}.bag.active: the file is larger"
        assert line.startswith(failure) and "buffering goes on" in line, err
        assert err.splitlines()[-1].startswith("rostools: 1 snapshot not written whole"), err
    finally:
        snap.stop()
        pub.stop()
