"""The tables benchmark's own pieces (benchmarks/bench_tables.py), without its peers' venvs.

The benchmark runs for minutes against pip-installed peers; here only what it builds on: the
generated bag holds what it claims, in types every reader decodes, and a measured process
reports its peak RSS and is stopped at its limit.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import pytest

from benchmarks import bench_tables as bench


def test_the_generated_bag_holds_full_imu_and_cloud_messages(tmp_path: Path) -> None:
    """One second of recording: 1,000 Imu and 10 PointCloud2 messages, decodable by their
    full definitions (which the bag carries for rosbags, bagpy and rostopic), in time order."""
    from rostools.bag.formats.access import open_bag
    from rostools.msgs.codec import Codec
    from rostools.msgs.store import TypeStore

    bag = bench._write_bag(tmp_path / "one.bag", 1)
    data = bench.Data(bag, 1, bag, 1)
    codec = Codec.of(TypeStore.default())  # rostools' own decoder, not the one under test
    seen: dict[str, list[int]] = {bench.IMU: [], bench.CLOUD: []}
    last: dict[str, object] = {}
    store = TypeStore.default()
    with open_bag(bag) as reader:
        for conn, _, payload in reader.messages():
            assert conn.definition == store.full_text(conn.type)
            assert conn.md5sum == store.md5(conn.type)
            assert len(payload) == data.message_bytes(conn.topic)
            decoded = codec.decode(conn.type, payload)
            seen[conn.topic].append(decoded.header.seq)
            last[conn.topic] = decoded
    assert seen[bench.IMU] == list(range(data.rows(bench.IMU)))
    assert seen[bench.CLOUD] == list(range(data.rows(bench.CLOUD)))
    cloud: Any = last[bench.CLOUD]
    assert cloud.width * cloud.point_step == len(cloud.data) == bench.CLOUD_POINTS * 16
    assert [f.name for f in cloud.fields] == ["x", "y", "z", "intensity"]


def test_a_measured_process_reports_its_own_memory_not_the_benchmarks() -> None:
    """The command's peak RSS is its own: a process the benchmark starts directly would have
    the benchmark's peak as a floor (vfork, then exec, keeps the old high-water mark)."""
    ballast = bytearray(300 << 20)  # the benchmark's process, holding data
    ballast[::4096] = b"x" * len(ballast[::4096])
    code = (
        "import json; b = bytearray(64 << 20); b[::4096] = b'x' * len(b[::4096]); "
        "print(json.dumps({'rows': 3, 'seconds': 1}))"
    )
    run = bench._measure([sys.executable, "-c", code])
    assert run.reported() == {"rows": 3, "seconds": 1}
    assert 64 <= run.rss_mb < 200
    assert run.lines == 1
    assert not run.stopped
    del ballast


def test_a_measured_process_tree_counts_every_process_anonymous_memory() -> None:
    child = "import time; b = bytearray(80 << 20); b[::4096] = b'x' * len(b[::4096]); time.sleep(1)"
    code = f"import subprocess, sys; subprocess.run([sys.executable, '-c', {child!r}])"
    run = bench._measure([sys.executable, "-c", code])
    assert run.anon_mb >= 80


def test_a_measured_process_is_stopped_at_its_limit() -> None:
    """The bound on a slow peer: killed past its limit, what it printed kept."""
    code = "import time; print('row', flush=True); time.sleep(600)"
    run = bench._measure([sys.executable, "-c", code], limit=1.0)
    assert run.stopped
    assert (run.lines, run.tail) == (1, b"row\n")


def test_a_failing_command_is_an_error_naming_it() -> None:
    with pytest.raises(RuntimeError, match="boom"):
        bench._measure([sys.executable, "-c", "raise SystemExit('boom')"])


def test_the_benchmark_is_registered() -> None:
    from benchmarks import run

    assert "benchmarks.bench_tables" in run.MODULES
    assert set(bench.BENCHMARKS) == {"tables_topics", "tables_whole_bag", "tables_many_bags"}
