"""The live table of ``bag record`` on a terminal (issue 13: its last frame)."""

from __future__ import annotations

import io
import time
from pathlib import Path
from typing import Any

from rich.console import Console

from rostools.bag.live.follow import TopicStats
from rostools.cli.bag.record import LiveTable


class _Recorder:
    """What the table reads of a recorder."""

    def __init__(self, folder: Path) -> None:
        self.stats = {"/chatter": TopicStats("std_msgs/String", messages=20, bytes=400, written=19)}
        self.connected = 2
        self.current_file = folder / "x.bag.active"
        self.closed_files: list[Path] = []
        self.started = time.monotonic() - 3

    def publishers(self, topic: str) -> int:
        return self.connected


def _row(table: LiveTable, rec: Any) -> list[str]:
    console = Console(file=io.StringIO(), width=200)
    console.print(table._table(rec, time.monotonic()))
    out = console.file.getvalue()  # type: ignore[attr-defined]
    line = next(x for x in out.splitlines() if "/chatter" in x)
    return [cell.strip() for cell in line.strip("│ ").split("│")]


def test_last_frame_keeps_the_publishers_and_counts_what_was_written(tmp_path: Path) -> None:
    rec = _Recorder(tmp_path)
    table = LiveTable()
    table.tick(rec)  # type: ignore[arg-type]
    rec.connected = 0  # the recorder has unsubscribed by the last frame
    table.last_frame(rec)  # type: ignore[arg-type]
    row = _row(table, rec)
    assert row[:4] == ["/chatter", "std_msgs/String", "2", "19"], row


def test_last_frame_says_the_size_of_the_closed_file(tmp_path: Path) -> None:
    # the defect: the .active file was renamed by then, and the title said "0 B written"
    rec = _Recorder(tmp_path)
    (tmp_path / "x.bag").write_bytes(b"x" * 5000)
    rec.closed_files = [tmp_path / "x.bag"]
    console = Console(file=io.StringIO(), width=200)
    console.print(LiveTable()._table(rec, time.monotonic()))
    title = console.file.getvalue().splitlines()[0]  # type: ignore[attr-defined]
    assert title.startswith("recording x.bag: 4.9 KB written"), title
