"""The writers' output: coalescing, by-reference payloads, partial writes."""

from __future__ import annotations

import errno
import os
from pathlib import Path

import pytest

from rostools.bag.formats import sink as sink_module
from rostools.bag.formats.sink import BIG_PAYLOAD, Sink, WriteError, frozen


def test_partial_writes_are_completed(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    real = os.writev

    def stingy(fd: int, buffers: list[bytes]) -> int:  # the kernel may take any prefix
        first = bytes(buffers[0])[:7]
        return real(fd, [first])

    monkeypatch.setattr(sink_module.os, "writev", stingy)
    path = tmp_path / "out"
    fd = os.open(path, os.O_WRONLY | os.O_CREAT)
    out = Sink(fd, str(path))
    pieces = [b"small", os.urandom(BIG_PAYLOAD + 3), b"tail", memoryview(os.urandom(BIG_PAYLOAD))]
    for piece in pieces:
        out.write(piece)
    assert out.tell() == sum(len(p) for p in pieces)
    out.flush()
    os.close(fd)
    assert path.read_bytes() == b"".join(bytes(p) for p in pieces)
    assert out.pending() == 0
    assert out.written == out.tell()


def test_mutable_payloads_are_copied() -> None:
    data = bytearray(b"abc")
    kept = frozen(data)
    data[0] = ord("x")
    assert kept == b"abc"
    view = memoryview(b"read-only")
    assert frozen(view) is view


def test_a_reused_buffer_does_not_change_written_messages(tmp_path: Path) -> None:
    from rostools.bag.formats.access import open_bag, open_writer

    for name in ("x.bag", "x.mcap"):
        writer = open_writer(tmp_path / name, compression="none")
        conn = writer.add_connection("/t", "std_msgs/Empty", "d41d8cd98f00b204e9800998ecf8427e", "")
        buf = bytearray(BIG_PAYLOAD * 2)
        for i in range(3):
            buf[0] = i
            writer.write(conn, i, buf)
        writer.close()
        with open_bag(tmp_path / name) as reader:
            assert [bytes(d)[0] for _, _, d in reader.messages()] == [0, 1, 2]


def _full_disk(monkeypatch: pytest.MonkeyPatch, after: int = 0) -> None:
    """Writes succeed for ``after`` bytes, then fail as on a full disk (ENOSPC)."""
    real = os.writev
    room = [after]

    def full(fd: int, buffers: list[bytes]) -> int:
        if room[0] <= 0:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        first = bytes(buffers[0])[: room[0]]
        room[0] -= len(first)
        return real(fd, [first])

    monkeypatch.setattr(sink_module.os, "writev", full)


def test_after_a_failed_write_nothing_more_is_written(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # The tail of the file is a record cut short: anything appended later (an index on close,
    # once some space is freed) would land after it, where no reader looks for it.
    path = tmp_path / "out"
    fd = os.open(path, os.O_WRONLY | os.O_CREAT)
    out = Sink(fd, str(path))
    _full_disk(monkeypatch, after=5)
    out.write(b"0123456789")
    with pytest.raises(WriteError, match=r"cannot write .*out: the disk is full") as failed:
        out.flush()
    assert failed.value.disk_full
    monkeypatch.undo()  # space again
    out.write(b"more")
    with pytest.raises(WriteError):
        out.flush()
    with pytest.raises(WriteError):
        out.pwrite(b"X", 0)
    os.close(fd)
    assert path.read_bytes() == b"01234"


@pytest.mark.parametrize("name", ["x.bag", "x.mcap"])
def test_a_writer_on_a_full_disk_leaves_no_file_and_no_descriptor(
    name: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    from rostools.bag.formats.access import open_writer

    _full_disk(monkeypatch)
    fds = len(os.listdir("/proc/self/fd"))
    with pytest.raises(WriteError, match="the disk is full"):
        open_writer(tmp_path / name)
    assert len(os.listdir("/proc/self/fd")) == fds
    assert not (tmp_path / name).exists()
