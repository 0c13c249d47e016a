"""The live table of ``bag snapshot``: per topic the buffer's fill, time span and evictions."""

from __future__ import annotations

import io
from pathlib import Path
from types import SimpleNamespace
from typing import Any

from rich.console import Console

from rostools.bag.live.ringbuffer import ConnInfo
from rostools.bag.live.snapshot import SnapshotOptions, Snapshotter
from rostools.cli.bag.snapview import SnapshotTable

NS = 1_000_000_000


def test_each_topic_shows_its_fill_span_and_evictions(tmp_path: Path) -> None:
    node: Any = SimpleNamespace(resolve=lambda name: name, subscribers={})
    opts = SnapshotOptions(topics=["/scan"], base=tmp_path / "s.bag", duration=2.0)
    snap = Snapshotter(node, opts)
    conn = ConnInfo("/scan", {"type": "sensor_msgs/LaserScan"})
    tb = snap.ring.topic("/scan")
    for i in range(10):  # 1 kB every half second: the 2 s limit keeps the last 5
        snap.ring.add(tb, conn, i * NS // 2, [bytes(1000)])
    snap.stats["/scan"] = SimpleNamespace(type="sensor_msgs/LaserScan", messages=10)  # type: ignore[assignment]
    console = Console(file=io.StringIO(), width=200)
    console.print(SnapshotTable()._view(snap))
    out = console.file.getvalue()  # type: ignore[attr-defined]
    row = next(line for line in out.splitlines() if "/scan" in line)
    cells = [cell.strip() for cell in row.strip("│ ").split("│")]
    assert cells[:6] == ["/scan", "sensor_msgs/LaserScan", "0", "5", "5.7 KB", "2.0 s"], cells
    assert cells[-1] == "5", cells  # evicted
    assert "keys: s snapshot, p pause, r resume" in out
