"""``bag record`` when the disk fills up.

With ``-L`` it stops in time, closes the file, and keeps what it wrote. When a write fails
(a disk really full, a file-size limit) it stops with one line and exit 6, and leaves the file
``.active`` for ``bag recover``.
"""

from __future__ import annotations

import asyncio
import functools
import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest

from rostools.bag.formats.access import open_bag
from rostools.bag.live import follow, recorder
from rostools.errors import RostoolsError
from rostools.master.server import MasterThread
from rostools.msgs.topictype import TopicType
from rostools.node.node import LiveNode
from tests.support.env import CLI, run_cli
from tests.support.procs import Proc, start_cli

STRING = TopicType("std_msgs/String", "992ce8a1687cec8c8bd883ec73ca41d1", "string data\n")


def test_a_filling_disk_stops_the_recording_cleanly(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    free = [10 * 1024**3]
    monkeypatch.setattr(follow, "free_bytes", lambda folder: free[0])
    monkeypatch.setattr(recorder, "DISK_PERIOD", 0.05)
    opts = recorder.RecordOptions(topics=["/t"], base=tmp_path / "x.bag", min_space=1024**3)

    async def main(uri: str) -> int:
        pub_node = await LiveNode("pub", uri).start()
        rec_node = await LiveNode("rec", uri).start()
        try:
            pub = await pub_node.advertise("/t", STRING)
            rec = recorder.Recorder(rec_node, opts)
            task = asyncio.ensure_future(rec.run(asyncio.Event()))
            while pub.subscriber_count == 0:
                await asyncio.sleep(0.01)
            sent = 0
            while sent < 50 or rec.stats["/t"].written < 50:
                pub.publish_raw(struct.pack("<I", 1) + b"x")
                pub.flush()
                sent += 1
                await asyncio.sleep(0.002)
            free[0] = 512 * 1024**2  # below -L: the next check stops the recording
            with pytest.raises(RostoolsError, match=r"less than 1G free .* recording stopped"):
                await asyncio.wait_for(task, 10)
            return rec.stats["/t"].written
        finally:
            await rec_node.close()
            await pub_node.close()

    with MasterThread() as master:
        written = asyncio.run(main(master.uri))
    assert not list(tmp_path.glob("*.active"))  # closed and renamed
    with open_bag(tmp_path / "x.bag") as reader:
        assert reader.info().indexed
        assert len(list(reader.messages())) == written >= 50


#: 20 KB a message, 200 a second: a 1 MiB disk fills within a second.
PAYLOAD = "x" * 20_000
#: Kept small so that whole chunks reach the small disk before it fills.
CHUNK_KB = "64"
DISK = "1m"
FORMATS = {"bag": ["-s", "bag"], "mcap": ["-s", "mcap", "--compression", "none"]}


@functools.cache
def _no_tmpfs() -> str | None:
    """Why a tmpfs cannot be mounted in a private mount namespace here, or None."""
    if os.geteuid() != 0:
        return "a real full disk needs root (a tmpfs in a private mount namespace)"
    if shutil.which("unshare") is None:
        return "unshare (util-linux) is not installed"
    with tempfile.TemporaryDirectory() as where:
        probe = subprocess.run(
            ["unshare", "-m", "mount", "-t", "tmpfs", "-o", "size=64k", "tmpfs", where],
            capture_output=True,
            text=True,
            check=False,
        )
    if probe.returncode != 0:
        return f"cannot mount a tmpfs in a mount namespace: {probe.stderr.strip()}"
    return None


@pytest.fixture
def publisher(rostools_master: str, cli_env: dict[str, str]) -> Iterator[Proc]:
    """``/t`` at 200 Hz, 20 KB a message, until the test ends."""
    pub = start_cli(
        "topic", "pub", "-r", "200", "/t", "std_msgs/String", f"data: {PAYLOAD}", env=cli_env
    )
    try:
        yield pub
    finally:
        pub.stop()


def _said_once(code: int, err: str, active: str, why: str) -> None:
    """A write that failed: exit 6, one line naming the file, ``why``, and the recover command."""
    assert code == 6, err
    assert "Traceback" not in err
    assert err.count("\n") == 1 and err.startswith(f"rostools: cannot write {active}: "), err
    assert why in err and f"rostools bag recover {active}" in err, err


def _record_until_it_stops(argv: list[str], env: dict[str, str]) -> tuple[int, str]:
    """Run a recorder that is expected to stop by itself; its exit code and stderr."""
    rec = Proc(argv, env=env)
    try:
        code = rec.popen.wait(60)
        return code, rec.output()[1]
    finally:
        rec.stop()


def _recovered_messages(active: Path, env: dict[str, str]) -> list[bytes]:
    """``bag recover`` on a recording cut short: the messages it gets back."""
    done = run_cli("bag", "recover", str(active), "-F", "json", env=env)
    assert done.returncode in (0, 6), done.stderr  # 6: the record cut in two is lost
    assert "Traceback" not in done.stderr
    with open_bag(Path(json.loads(done.stdout)["output"])) as reader:
        return [bytes(data) for _, _, data in reader.messages(["/t"])]


@pytest.mark.parametrize("fmt", sorted(FORMATS))
def test_a_full_disk_stops_with_one_line_and_exit_6(
    fmt: str, publisher: Proc, cli_env: dict[str, str], tmp_path: Path
) -> None:
    """ENOSPC on a real (tmpfs) disk: no traceback, one line, exit 6, and recoverable."""
    if (why := _no_tmpfs()) is not None:
        pytest.skip(why)
    disk, kept = tmp_path / "disk", tmp_path / "kept"
    disk.mkdir()
    kept.mkdir()
    out = disk / f"x.{fmt}"
    # The tmpfs exists only in the recorder's mount namespace: copy the file out before it goes.
    script = (
        "disk=$1 kept=$2; shift 2; mount -t tmpfs -o size=" + DISK + ' tmpfs "$disk" || exit 99;'
        ' "$@"; code=$?; cp "$disk"/* "$kept"/; exit $code'
    )
    code, err = _record_until_it_stops(
        ["unshare", "-m", "sh", "-c", script, "sh", str(disk), str(kept),
         *CLI, "bag", "record", "-q", "-L", "0", "/t", "-O", str(out),
         "--chunksize", CHUNK_KB, *FORMATS[fmt]],
        cli_env,
    )  # fmt: skip
    active = f"{out}.active"
    _said_once(code, err, active, "the disk is full")
    assert [p.name for p in kept.iterdir()] == [f"x.{fmt}.active"]
    messages = _recovered_messages(kept / f"x.{fmt}.active", cli_env)
    assert messages and all(
        m == struct.pack("<I", len(PAYLOAD)) + PAYLOAD.encode() for m in messages
    )


def test_a_disk_full_from_the_start_leaves_no_file(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    if (why := _no_tmpfs()) is not None:
        pytest.skip(why)
    disk = tmp_path / "disk"
    disk.mkdir()
    out = disk / "x.bag"
    script = (
        'disk=$1; shift; mount -t tmpfs -o size=64k tmpfs "$disk" || exit 99;'
        ' head -c 100000 /dev/zero > "$disk/filler" 2>/dev/null;'
        ' "$@"; code=$?; ls "$disk" >&2; exit $code'
    )
    code, err = _record_until_it_stops(
        ["unshare", "-m", "sh", "-c", script, "sh", str(disk),
         *CLI, "bag", "record", "-q", "-L", "0", "/t", "-O", str(out)],
        cli_env,
    )  # fmt: skip
    assert code == 6, err
    line, listing = err.split("\n", 1)
    assert line == (
        f"rostools: cannot write {out}.active: the disk is full (No space left on device):"
        " the recording stopped (hint: free some space)"
    )
    assert listing.split() == ["filler"]  # no empty or partial bag left behind


def test_a_file_size_limit_stops_with_one_line_and_exit_6(
    publisher: Proc, cli_env: dict[str, str], tmp_path: Path
) -> None:
    """EFBIG from ``ulimit -f`` (no root needed): the same clean stop."""
    limit = 512 * 1024
    out = tmp_path / "x.bag"
    # Python ignores SIGXFSZ, so a write past the limit fails with EFBIG instead of killing it.
    launcher = (
        "import os, resource, sys;"
        f"resource.setrlimit(resource.RLIMIT_FSIZE, ({limit}, {limit}));"
        "os.execv(sys.executable, [sys.executable, '-m', 'rostools', *sys.argv[1:]])"
    )
    code, err = _record_until_it_stops(
        [sys.executable, "-c", launcher, "bag", "record", "-q", "-L", "0", "/t", "-O", str(out),
         "--chunksize", CHUNK_KB],
        cli_env,
    )  # fmt: skip
    active = f"{out}.active"
    _said_once(code, err, active, "size limit")
    assert Path(active).stat().st_size == limit
    assert _recovered_messages(Path(active), cli_env)


def test_a_topic_without_messages_shows_the_type_the_master_knows(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    # the defect: "/rosout [?]" in the summary, although the master knows its type
    done = run_cli("bag", "record", "-a", "--duration", "1.5", "-O", str(tmp_path / "x.bag"),
                   env=cli_env, timeout=60)  # fmt: skip
    assert done.returncode == 0, done.stderr
    lines = [line.strip() for line in done.stderr.splitlines()]
    assert "/rosout_agg [rosgraph_msgs/Log]: 0 msgs" in lines, done.stderr
