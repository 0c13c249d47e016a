"""``trigger_snapshot`` on the wire: rosbag_snapshot's type and md5sum, requests, names."""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace
from typing import Any

import pytest

from rostools.bag.live.snapshot import SnapshotOptions, Snapshotter, check_remote_name
from rostools.bag.live.snapshot_srv import (
    FOREVER_SECS,
    SnapshotRequest,
    TriggerError,
    decode_answer,
    encode_answer,
    window,
)
from rostools.errors import InvalidDataError


def test_requests_and_answers_round_trip() -> None:
    request = SnapshotRequest("crash.bag", ["/a", "/tf"], 1_500_000_000, 2_250_000_001)
    assert SnapshotRequest.decode(request.encode()) == request
    assert SnapshotRequest.decode(SnapshotRequest().encode()) == SnapshotRequest()  # times 0
    assert decode_answer(encode_answer(True, "crash.bag")) == (True, "crash.bag")
    refused = "no messages buffered on selected topics"
    assert decode_answer(encode_answer(False, refused)) == (False, refused)
    with pytest.raises(InvalidDataError, match=r"^an empty answer$"):
        decode_answer(b"")


def test_times_outside_ros_time_are_sent_at_its_ends() -> None:
    before_zero = SnapshotRequest(start_ns=-5, stop_ns=(FOREVER_SECS + 9) * NS)
    back = SnapshotRequest.decode(before_zero.encode())
    assert (back.start_ns, back.stop_ns // NS) == (0, FOREVER_SECS)
    assert back.forever


def test_many_empty_topic_names_are_a_request() -> None:
    """rosbag_snapshot's clients send empty names for none; each takes its 4 length bytes."""
    request = SnapshotRequest("x.bag", [""] * 20, 1, 2)
    assert SnapshotRequest.decode(request.encode()) == request


NS = 1_000_000_000


def test_every_trigger_works_its_window_out_alike(tmp_path: Path) -> None:
    """``--before`` and ``--after`` are seconds, from the remote ``bag trigger`` or a local one."""
    now = 1_700_000_000 * NS
    assert window(now, 20.0, 10.0) == (now - 20 * NS, now + 10 * NS)
    assert window(now, 0.5, 0.0) == (now - NS // 2, 0)  # 0: up to the trigger
    assert window(now, None, 2.0) == (0, now + 2 * NS)  # 0: from the oldest buffered
    assert window(now, None, 0.0, forever=True)[1] == FOREVER_SECS * NS
    assert window(now, 20.0, 0.0, forever=True) == (now - 20 * NS, FOREVER_SECS * NS)
    # reaching back before time 0 starts at 1 ns: 0 would mean "from the oldest buffered"
    assert window(2 * NS, 5.0, 0.0) == (1, 0)
    node: Any = SimpleNamespace(resolve=lambda name: name)
    opts = SnapshotOptions(topics=["/a"], base=tmp_path / "s.bag", before=3.0, after=2.0)
    snap = Snapshotter(node, opts)  # the local path: a signal, a key, ~trigger
    snap.clock = SimpleNamespace(now=lambda: now)  # type: ignore[assignment]
    local = snap.local_request()
    assert (local.start_ns, local.stop_ns) == (now - 3 * NS, now + 2 * NS)


@pytest.mark.parametrize(
    ("data", "why"),
    [
        (b"", "the request is cut short at byte 0"),
        (b"\x05\x00\x00\x00ab", "the request is cut short at byte 4"),
        (b"\x00\x00\x00\x00\xff\xff\xff\xff", "a list of 4294967295 items in 8 bytes"),
        (b"\x00\x00\x00\x00\x03\x00\x00\x00" + bytes(8), "a list of 3 items in 16 bytes"),
        (b"\x01\x00\x00\x00\xff", "a string that is not UTF-8 (invalid start byte)"),
    ],
    ids=["empty", "cut string", "a list longer than the bytes", "a list a little long", "utf-8"],
)
def test_a_bad_request_is_refused_without_allocating(data: bytes, why: str) -> None:
    with pytest.raises(InvalidDataError) as refused:
        SnapshotRequest.decode(data)
    assert str(refused.value) == why


@pytest.mark.parametrize("name", ["../x.bag", "a/b.bag", "/tmp/x.bag", "..", "a\\b", "x\0.bag"])
def test_a_remote_name_cannot_leave_the_folder(name: str) -> None:
    with pytest.raises(TriggerError) as refused:
        check_remote_name(name)
    assert str(refused.value) == (
        f"refused the file name {name!r}: a trigger names a file in the output folder, "
        "without '/' or '..'"
    )


def test_file_names_follow_rosbag_snapshot_and_never_collide(tmp_path: Path) -> None:
    node: Any = SimpleNamespace(resolve=lambda name: name)
    opts = SnapshotOptions(topics=["/a"], base=tmp_path / "snapshot.bag", name="run.bag")
    snap = Snapshotter(node, opts)
    assert snap._file_spec("").path == tmp_path / "run.bag"
    (tmp_path / "run.bag").touch()
    (tmp_path / "run_1.bag.active").touch()  # being written by another recorder
    assert snap._file_spec("").path == tmp_path / "run_2.bag"
    given = snap._file_spec("crash.mcap")
    assert (given.path, given.format) == (tmp_path / "crash.mcap", "mcap")
    dated = snap._file_spec("test").path.name  # rosbag_snapshot: test -> test<date>.bag
    assert dated.startswith("test2") and dated.endswith(".bag")
