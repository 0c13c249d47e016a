"""Bags as tables (issue 38): ``bag export`` to Parquet beside the tools people use today.

One generated bag (1 GB by default) of an Imu-like topic at 1 kHz and a PointCloud2-like one
at 10 Hz, written once with our writer into ``benchmarks/build/tables/`` (gitignored) with
the full message definitions, so that every peer decodes it. Side by side in one run:

- ours: ``rostools bag export BAG -o OUT --format parquet -t TOPIC`` (whole process), and the
  streaming API ``rostools.bag_batches`` drained in-process;
- rosbags-dataframe (``get_dataframe``, one topic at a time, to pandas, every field), in its
  own venv; bagpy (``message_by_topic``, to CSV) in a venv over the system Python, on a
  subset of the bag (it holds every message in memory before writing); ``rostopic echo -b BAG
  -p TOPIC`` (real ROS 1), stopped after ``ROSTOOLS_BENCH_TABLES_PEER_S`` seconds, its rate
  the rows it printed by then;
- the ceiling: ``pyarrow.parquet.write_table`` of the same table, already in memory.

Rows/s, MB/s (message bytes of the topic per second) and memory, both ways: peak RSS
(``ru_maxrss`` from ``os.wait4`` of the command, run by a small launcher so that it is the
command's own: its largest process, the bag's mmapped pages included) and peak anonymous
memory (RssAnon summed over the command's process tree, polled every 20 ms). Then 100 small
bags exported with ``-j 1`` and ``-j 2`` and the same export function mapped over a Dask
``LocalCluster`` of two worker processes.

Knobs (environment): ``ROSTOOLS_BENCH_TABLES_MB`` (bag size, default 1000; 100 while
developing), ``ROSTOOLS_BENCH_TABLES_BAGS`` (default 100), ``ROSTOOLS_BENCH_TABLES_PEER_S``
(default 120). The peers' venvs are installed here with pip, never in the project's.
"""

from __future__ import annotations

import json
import os
import shutil
import statistics
import struct
import subprocess
import sys
import tempfile
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from benchmarks.common import ROOT, SYSTEM_PYTHON, Result, have, rostools_cmd

BUILD = ROOT / "benchmarks" / "build" / "tables"
PEERS = ROOT / "benchmarks" / "build" / "tables-peers"
SIZE_MB = int(os.environ.get("ROSTOOLS_BENCH_TABLES_MB", "1000"))
BAG_COUNT = int(os.environ.get("ROSTOOLS_BENCH_TABLES_BAGS", "100"))
PEER_SECONDS = float(os.environ.get("ROSTOOLS_BENCH_TABLES_PEER_S", "120"))
#: Our runs take seconds, and the machine's load moves them: the median of three. A peer's
#: take minutes: one each.
OUR_REPEATS = 3
#: Seconds of recording in each of the many small bags (about 10 MB each): enough work that
#: starting two worker processes (about 0.5 s of CPU) does not hide what -j 2 gains.
SMALL_SECONDS = 6
IMU_HZ = 1000
CLOUD_HZ = 10
CLOUD_POINTS = 8192
POINT_STEP = 16
T0 = 1_700_000_000
IMU, CLOUD = "/imu/data", "/points"
#: rosbags-dataframe takes the fields it extracts by name: every field of each type.
DF_KEYS = {
    IMU: "header.seq,header.stamp,header.frame_id,orientation.x,orientation.y,orientation.z,"
    "orientation.w,orientation_covariance,angular_velocity.x,angular_velocity.y,"
    "angular_velocity.z,angular_velocity_covariance,linear_acceleration.x,"
    "linear_acceleration.y,linear_acceleration.z,linear_acceleration_covariance",
    CLOUD: "header.seq,header.stamp,header.frame_id,height,width,fields,is_bigendian,"
    "point_step,row_step,data,is_dense",
}
PEER_PACKAGES = {
    "rosbags": ["rosbags==0.11.9", "rosbags-dataframe==0.10.2", "pandas"],
    "bagpy": ["bagpy==0.5"],
}
#: What our venv needs beside rostools: the ``arrow`` extra's pyarrow, and Dask.
OUR_EXTRAS = ["pyarrow", "dask[distributed]"]

_HEADER = struct.Struct("<III")
_CLOUD_FIELDS = b"".join(
    struct.pack("<I", len(name)) + name + struct.pack("<IBI", 4 * i, 7, 1)
    for i, name in enumerate((b"x", b"y", b"z", b"intensity"))
)


# -- the data ---------------------------------------------------------------------------------


def _imu_payloads(count: int, first: int, seed: int) -> list[bytes]:
    """``count`` sensor_msgs/Imu messages, every one different (37 float64 after the header)."""
    import numpy as np

    values = np.random.default_rng(seed).normal(0.0, 1.0, (count, 37))
    head = struct.pack("<I", 8) + b"imu_link"
    out = []
    for i in range(count):
        n = first + i
        secs, nsecs = T0 + n // IMU_HZ, (n % IMU_HZ) * (1_000_000_000 // IMU_HZ)
        out.append(_HEADER.pack(n, secs, nsecs) + head + values[i].tobytes())
    return out


def _cloud_payload(n: int, pool: bytes) -> bytes:
    """The n-th sensor_msgs/PointCloud2: a distinct slice of a random pool as its points."""
    size = CLOUD_POINTS * POINT_STEP
    offset = (n * 4099) % (len(pool) - size)
    secs, nsecs = T0 + n // CLOUD_HZ, (n % CLOUD_HZ) * (1_000_000_000 // CLOUD_HZ)
    return b"".join(
        (
            _HEADER.pack(n, secs, nsecs),
            struct.pack("<I", 8) + b"velodyne",
            struct.pack("<III", 1, CLOUD_POINTS, 4) + _CLOUD_FIELDS,
            struct.pack("<BIII", 0, POINT_STEP, size, size),
            pool[offset : offset + size],
            b"\x01",
        )
    )


def _write_bag(path: Path, seconds: int, seed: int = 38) -> Path:
    """A deterministic bag of ``seconds`` of recording, written once and kept."""
    if path.exists():
        return path
    import numpy as np

    from rostools.bag.formats.access import open_writer
    from rostools.msgs.store import TypeStore

    store = TypeStore.default()
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp")
    tmp.unlink(missing_ok=True)
    pool = np.random.default_rng(seed).normal(0, 20, 1 << 20).astype(np.float32).tobytes()
    with open_writer(tmp, format="bag") as writer:
        conns = {
            topic: writer.add_connection(
                topic, kind, store.md5(kind), store.full_text(kind), callerid="/robot"
            )
            for topic, kind in ((IMU, "sensor_msgs/Imu"), (CLOUD, "sensor_msgs/PointCloud2"))
        }
        per_cloud = IMU_HZ // CLOUD_HZ
        for second in range(seconds):
            imus = _imu_payloads(IMU_HZ, second * IMU_HZ, seed + second)
            for i, payload in enumerate(imus):
                n = second * IMU_HZ + i
                writer.write(conns[IMU], T0 * 10**9 + n * (10**9 // IMU_HZ), payload)
                if i % per_cloud == 0:
                    c = n // per_cloud
                    stamp = T0 * 10**9 + c * (10**9 // CLOUD_HZ) + 1
                    writer.write(conns[CLOUD], stamp, _cloud_payload(c, pool))
    tmp.rename(path)
    return path


def _bytes_per_second() -> int:
    imu = len(_imu_payloads(1, 0, 0)[0])
    cloud = len(_cloud_payload(0, bytes(CLOUD_POINTS * POINT_STEP + 1)))
    return IMU_HZ * imu + CLOUD_HZ * cloud


@dataclass
class Data:
    """The big bag, the subset bagpy reads, and what each holds."""

    bag: Path
    seconds: int
    subset: Path
    subset_seconds: int

    def rows(self, topic: str, subset: bool = False) -> int:
        """Messages on ``topic`` in the bag (or the subset)."""
        seconds = self.subset_seconds if subset else self.seconds
        return seconds * (IMU_HZ if topic == IMU else CLOUD_HZ)

    def message_bytes(self, topic: str) -> int:
        """Bytes of one message on ``topic`` (every message of a topic has the same size)."""
        if topic == IMU:
            return len(_imu_payloads(1, 0, 0)[0])
        return len(_cloud_payload(0, bytes(CLOUD_POINTS * POINT_STEP + 1)))


def _data() -> Data:
    seconds = max(1, SIZE_MB * 1_000_000 // _bytes_per_second())
    subset_seconds = max(1, seconds // 10)
    return Data(
        _write_bag(BUILD / f"tables-{SIZE_MB}mb.bag", seconds),
        seconds,
        _write_bag(BUILD / f"tables-{SIZE_MB}mb-subset.bag", subset_seconds),
        subset_seconds,
    )


def _small_bags() -> list[Path]:
    folder = BUILD / f"many-{BAG_COUNT}x{SMALL_SECONDS}s"
    return [_write_bag(folder / f"run{i:03d}.bag", SMALL_SECONDS, seed=i) for i in range(BAG_COUNT)]


# -- the venvs ---------------------------------------------------------------------------------


def _peer_python(name: str) -> str | None:
    """The interpreter of a peer's venv, installed on first use; None if pip cannot."""
    venv = PEERS / name
    stamp = venv / ".installed"
    packages = PEER_PACKAGES[name]
    if not stamp.exists() or stamp.read_text() != " ".join(packages):
        # bagpy imports rospy's genpy-generated types: the venv sees the system's ROS 1.
        base = SYSTEM_PYTHON if name == "bagpy" else sys.executable
        if name == "bagpy" and not Path(SYSTEM_PYTHON).exists():
            return None
        extra = ["--system-site-packages"] if name == "bagpy" else []
        if not (venv / "bin" / "python").exists():
            subprocess.run([base, "-m", "venv", *extra, str(venv)], check=True)
        pip = subprocess.run(
            [str(venv / "bin" / "pip"), "install", "-q", *packages],
            capture_output=True,
            check=False,
        )
        if pip.returncode != 0:
            return None
        stamp.write_text(" ".join(packages))
    return str(venv / "bin" / "python")


def _our_python() -> str:
    """The benchmark venv's interpreter (a normal install of rostools), with pyarrow and Dask."""
    python = str(Path(rostools_cmd()[0]).parent / "python")
    probe = subprocess.run(
        [python, "-c", "import pyarrow, dask.distributed"], capture_output=True, check=False
    )
    if probe.returncode != 0:
        subprocess.run([python, "-m", "pip", "install", "-q", *OUR_EXTRAS], check=True)
    return python


# -- one measured process ----------------------------------------------------------------------


#: Runs the measured command as its own child, so that the command's ``ru_maxrss`` is its own:
#: a child that Python starts by vfork inherits the starter's peak RSS as a floor (exec records
#: the old address space's high-water mark), and the benchmark's process holds hundreds of MB.
#: Meanwhile it sums RssAnon over the command's process tree every 20 ms: the anonymous memory
#: (the bag's mmapped pages, which RSS counts and the kernel can drop, are not in it).
LAUNCHER = r"""
import json, os, signal, sys, time
report, limit, argv = sys.argv[1], float(sys.argv[2]), sys.argv[3:]
def tree(pid):
    pids, todo = [], [pid]
    while todo:
        p = todo.pop()
        pids.append(p)
        try:
            for task in os.listdir(f"/proc/{p}/task"):
                with open(f"/proc/{p}/task/{task}/children") as f:
                    todo += [int(c) for c in f.read().split()]
        except OSError:
            pass
    return pids
def anon_kb(pids):
    total = 0
    for p in pids:
        try:
            with open(f"/proc/{p}/status") as f:
                total += sum(int(l.split()[1]) for l in f if l.startswith("RssAnon:"))
        except OSError:
            pass
    return total
start = time.perf_counter()
pid = os.fork()
if pid == 0:
    os.setsid()
    os.execvp(argv[0], argv)
stopped, peak = False, 0
while True:
    got, status, usage = os.wait4(pid, os.WNOHANG)
    if got:
        break
    peak = max(peak, anon_kb(tree(pid)))
    if limit > 0 and time.perf_counter() - start > limit:
        os.killpg(pid, signal.SIGKILL)
        _, status, usage = os.wait4(pid, 0)
        stopped = True
        break
    time.sleep(0.02)
with open(report, "w") as f:
    json.dump({"wall": time.perf_counter() - start, "maxrss_kb": usage.ru_maxrss,
               "anon_kb": peak, "stopped": stopped,
               "code": os.waitstatus_to_exitcode(status)}, f)
"""


@dataclass
class Run:
    """What one process did: wall seconds, peak RSS, its stdout, whether it was stopped."""

    wall: float
    rss_mb: float
    anon_mb: float
    lines: int
    tail: bytes
    stopped: bool

    def reported(self) -> dict[str, Any]:
        """The JSON the measured script printed last: its own count and seconds."""
        last = self.tail.decode(errors="replace").strip().splitlines()[-1]
        return dict(json.loads(last))


def _measure(argv: Sequence[str], *, limit: float | None = None) -> Run:
    """Run ``argv`` to its end (or ``limit`` seconds) through ``LAUNCHER``.

    Its stdout goes to a file on disk (``rostopic echo -p`` of clouds writes gigabytes): the
    lines are counted and only the tail is kept.
    """
    BUILD.mkdir(parents=True, exist_ok=True)
    with (
        tempfile.TemporaryFile(dir=BUILD) as out,
        tempfile.TemporaryFile(dir=BUILD) as err,
        tempfile.TemporaryDirectory(dir=BUILD) as tmp,
    ):
        report = Path(tmp) / "report.json"
        launcher = [sys.executable, "-c", LAUNCHER, str(report), str(limit or 0), *argv]
        subprocess.run(launcher, stdout=out, stderr=err, stdin=subprocess.DEVNULL, check=True)
        got = json.loads(report.read_text())
        lines, size = 0, out.seek(0, os.SEEK_END)
        out.seek(0)
        while chunk := out.read(1 << 20):
            lines += chunk.count(b"\n")
        out.seek(max(0, size - 65536))
        tail = out.read()
        err.seek(0)
        stderr = err.read()
    if got["code"] != 0 and not got["stopped"]:
        raise RuntimeError(f"{' '.join(argv)} failed: {stderr.decode(errors='replace')[-800:]}")
    return Run(
        got["wall"], got["maxrss_kb"] / 1024, got["anon_kb"] / 1024, lines, tail, got["stopped"]
    )


# -- the scripts each side runs ----------------------------------------------------------------

ROSBAGS_DF = r"""
import json, sys, time
from pathlib import Path
from rosbags.dataframe import get_dataframe
from rosbags.highlevel import AnyReader
start = time.perf_counter()
with AnyReader([Path(sys.argv[1])]) as reader:
    frame = get_dataframe(reader, sys.argv[2], sys.argv[3].split(","))
print(json.dumps({"rows": len(frame), "seconds": time.perf_counter() - start}))
"""

BAGPY_CSV = r"""
import csv, json, sys, time
from bagpy import bagreader
start = time.perf_counter()
written = bagreader(sys.argv[1]).message_by_topic(sys.argv[2])
csv.field_size_limit(sys.maxsize)  # a cloud's points are one cell
with open(written, newline="") as f:  # a row's quoted cells may span lines
    rows = sum(1 for _ in csv.reader(f)) - 1
print(json.dumps({"rows": rows, "seconds": time.perf_counter() - start}))
"""

OUR_BATCHES = r"""
import json, sys, time
from rostools import bag_batches  # loads pyarrow, as the peer's imports load pandas: not timed
start = time.perf_counter()
rows = sum(batch.num_rows for batch in bag_batches([sys.argv[1]], sys.argv[2]))
print(json.dumps({"rows": rows, "seconds": time.perf_counter() - start}))
"""

# The ceiling: the table is built first (not timed), then only pyarrow's writer is timed.
CEILING = r"""
import json, sys, time
import pyarrow.parquet as pq
import rostools
table = rostools.bag_table([sys.argv[1]], sys.argv[2])
start = time.perf_counter()
pq.write_table(table, sys.argv[3], compression="zstd")  # as bag export writes
print(json.dumps({"rows": table.num_rows, "seconds": time.perf_counter() - start}))
"""

COUNT_ROWS = r"""
import json, sys
import pyarrow.dataset as ds
print(json.dumps({"rows": ds.dataset(sys.argv[1], format="parquet").count_rows()}))
"""

# One export function, mapped by Dask's scheduler over the bags: no scheduler of ours.
DASK_EXPORT = r"""
import json, sys, time
from pathlib import Path
from dask.distributed import Client, LocalCluster
from rostools.bag.tables.dataset import export_bag
from rostools.bag.tables.export import plan_export, prepare_output
if __name__ == "__main__":
    out, bags = Path(sys.argv[1]), [Path(p) for p in sys.argv[3:]]
    up = time.perf_counter()
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        start = time.perf_counter()
        rounds = []
        for _ in range(int(sys.argv[2])):  # the first with workers fresh, as -j's are
            begin = time.perf_counter()
            prepare_output(out, overwrite=True)
            plan = plan_export(bags, out, fmt="parquet")
            exported = client.gather(client.map(export_bag, plan.tasks, pure=False))
            rounds.append(time.perf_counter() - begin)
    rows = sum(f.rows for bag in exported for f in bag.files)
    print(json.dumps({"rounds": rounds, "cluster_start": start - up, "rows": rows}))
"""


# -- the rows ---------------------------------------------------------------------------------


@dataclass
class Rate:
    """A side's rows in how many seconds, its peak RSS, and how it was bounded."""

    rows: int
    seconds: float
    rss_mb: float | None
    anon_mb: float | None
    how: str

    @property
    def per_second(self) -> float:
        """Rows per second."""
        return self.rows / self.seconds if self.seconds > 0 else 0.0


def _median(runs: Sequence[Run]) -> Run:
    """The run of median wall time, with the largest memory of them all."""
    middle = sorted(runs, key=lambda r: r.wall)[len(runs) // 2]
    return Run(
        middle.wall, max(r.rss_mb for r in runs), max(r.anon_mb for r in runs), middle.lines,
        middle.tail, middle.stopped,
    )  # fmt: skip


def _export(python: str, bag: Path, topic: str | None, out: Path) -> Rate:
    """``rostools bag export`` to Parquet, whole process, median of OUR_REPEATS; rows counted
    back from the dataset."""
    argv = [*rostools_cmd(), "bag", "export", str(bag), "-o", str(out), "--format", "parquet"]
    runs = []
    for _ in range(OUR_REPEATS):
        shutil.rmtree(out, ignore_errors=True)
        runs.append(_measure([*argv, "-t", topic] if topic else argv))
    rows = int(_measure([python, "-c", COUNT_ROWS, str(out)]).reported()["rows"])
    shutil.rmtree(out, ignore_errors=True)
    run = _median(runs)
    return Rate(rows, run.wall, run.rss_mb, run.anon_mb, f"whole process, median of {len(runs)}")


_RUNS: dict[tuple[str, ...], Run] = {}


def _script(
    python: str | None, code: str, *args: str, whole: bool = True, repeats: int = 1
) -> Rate | None:
    """A Python script's rate: whole-process wall, or the seconds it timed itself; the median
    of ``repeats`` runs.

    A peer's run is kept for the run's other rows (rosbags-dataframe takes a minute at 1 GB).
    """
    if python is None:
        return None
    key = (python, code, *args)
    if key not in _RUNS:
        runs = [_measure([python, "-c", code, *args]) for _ in range(repeats)]
        if not whole:  # the median of the seconds the script timed itself
            runs.sort(key=lambda r: float(r.reported()["seconds"]))
        _RUNS[key] = runs[len(runs) // 2] if not whole else _median(runs)
    run = _RUNS[key]
    got = run.reported()
    seconds = run.wall if whole else float(got["seconds"])
    how = "whole process" if whole else "in-process"
    if repeats > 1:
        how += f", median of {repeats}"
    return Rate(int(got["rows"]), seconds, run.rss_mb, run.anon_mb, how)


def _rostopic(bag: Path, topic: str) -> Rate | None:
    """``rostopic echo -b BAG -p TOPIC`` into a file, stopped after PEER_SECONDS."""
    if not have("rostopic"):
        return None
    with tempfile.TemporaryDirectory() as home:
        env_argv = ["env", f"ROS_HOME={home}", "rostopic", "echo", "-b", str(bag), "-p", topic]
        run = _measure(env_argv, limit=PEER_SECONDS)
    rows = max(0, run.lines - 1)  # the first line is the column names
    how = f"stopped after {PEER_SECONDS:.0f} s, rate of the rows printed" if run.stopped else ""
    return Rate(rows, run.wall, run.rss_mb, run.anon_mb, how or "whole process")


def _bagpy(data: Data, topic: str) -> Rate | None:
    python = _peer_python("bagpy")
    if python is None:
        return None
    with tempfile.TemporaryDirectory() as tmp:
        # bagpy writes its CSV into a folder named after the bag, next to it.
        bag = Path(tmp) / data.subset.name
        bag.symlink_to(data.subset)
        rate = _script(python, BAGPY_CSV, str(bag), topic)
    assert rate is not None
    rate.how = f"whole process, on the first {data.subset_seconds} s of the bag"
    return rate


def _load() -> str:
    """The machine's load, for the note: other work on the two cores moves every figure."""
    return f"; load average {os.getloadavg()[0]:.1f} on {os.cpu_count()} CPUs"


def _rows_for(topic: str, data: Data, ours: Rate, peers: dict[str, Rate | None]) -> list[Result]:
    """rows/s, MB/s and peak RSS of ours beside each peer, for one topic."""
    label = f"{topic} ({'Imu 1 kHz' if topic == IMU else 'PointCloud2 10 Hz, 128 KB'})"
    size = data.message_bytes(topic) / 1e6
    results = []
    for peer, theirs in peers.items():
        goal = ">= 10x" if peer == "rosbags-dataframe" else "faster than"
        met = None if theirs is None else (
            ours.per_second >= 10 * theirs.per_second if goal == ">= 10x"
            else ours.per_second > theirs.per_second
        )  # fmt: skip
        note = (
            f"ours: bag export --format parquet, {ours.how}, {ours.rows} rows; "
            + (f"theirs: {theirs.how}, {theirs.rows} rows" if theirs else "peer not installed")
            + _load()
        )
        name = f"bag export -> Parquet vs {peer}, {label}"
        their_rate = theirs.per_second if theirs else None
        results.append(Result(
            f"{name}: rows/s", "rows/s", ours.per_second, their_rate,
            f"{goal} {peer}", met, note,
        ))  # fmt: skip
        results.append(Result(
            f"{name}: MB/s", "MB/s", ours.per_second * size,
            None if their_rate is None else their_rate * size, "-", None,
            "message bytes of the topic per second",
        ))  # fmt: skip
        results += _memory_rows(name, ours, theirs)
    return results


def _memory_rows(name: str, ours: Rate, theirs: Rate | None) -> list[Result]:
    return [
        Result(
            f"{name}: peak RSS", "MB", ours.rss_mb or 0.0, theirs.rss_mb if theirs else None,
            "-", None, "ru_maxrss (os.wait4) of the command's largest process; it counts the "
            "pages of a bag read through mmap, which the kernel may drop",
        ),
        Result(
            f"{name}: peak anonymous memory", "MB", ours.anon_mb or 0.0,
            theirs.anon_mb if theirs else None, "-", None,
            "RssAnon summed over the command's process tree, polled every 20 ms",
        ),
    ]  # fmt: skip


def bench_topics() -> list[Result]:
    """Each topic to a table: ours beside rosbags-dataframe, bagpy, rostopic echo -p, pyarrow."""
    data = _data()
    python = _our_python()
    rosbags = _peer_python("rosbags")
    results: list[Result] = []
    for topic in (IMU, CLOUD):
        ours = _export(python, data.bag, topic, BUILD / "out-topic")
        peers = {
            "rosbags-dataframe": _script(rosbags, ROSBAGS_DF, str(data.bag), topic, DF_KEYS[topic]),
            "bagpy": _bagpy(data, topic),
            "rostopic echo -b -p": _rostopic(data.bag, topic),
        }
        results += _rows_for(topic, data, ours, peers)
        with tempfile.TemporaryDirectory() as tmp:
            ceiling = _script(
                python, CEILING, str(data.bag), topic, str(Path(tmp) / "t.parquet"),
                whole=False, repeats=OUR_REPEATS,
            )  # fmt: skip
        assert ceiling is not None
        results.append(Result(
            f"bag export -> Parquet vs pyarrow write_table (ceiling), {topic}: rows/s",
            "rows/s", ours.per_second, ceiling.per_second, ">= 0.5x pyarrow write_table",
            ours.per_second >= 0.5 * ceiling.per_second,
            "ours whole process (read, decode, write); theirs: pq.write_table (zstd, as "
            "export) of the same table built by rostools.bag_table, only the write timed",
        ))  # fmt: skip
        api = _script(python, OUR_BATCHES, str(data.bag), topic, whole=False, repeats=OUR_REPEATS)
        df = _script(rosbags, ROSBAGS_DF, str(data.bag), topic, DF_KEYS[topic], whole=False)
        assert api is not None
        results.append(Result(
            f"rostools.bag_batches vs rosbags get_dataframe, {topic}: rows/s", "rows/s",
            api.per_second, df.per_second if df else None, ">= 10x rosbags-dataframe",
            None if df is None else api.per_second >= 10 * df.per_second,
            "in-process, imports not timed: record batches drained vs a pandas DataFrame",
        ))  # fmt: skip
    return results


def bench_whole_bag() -> list[Result]:
    """The whole bag, every topic, to Parquet, beside rosbags-dataframe one topic at a time."""
    data = _data()
    python = _our_python()
    size = data.bag.stat().st_size / 1e6
    ours = _export(python, data.bag, None, BUILD / "out-whole")
    rosbags = _peer_python("rosbags")
    theirs = [_script(rosbags, ROSBAGS_DF, str(data.bag), t, DF_KEYS[t]) for t in (IMU, CLOUD)]
    their_s = None if None in theirs else sum(r.seconds for r in theirs if r)
    return [
        Result(
            f"bag export -> Parquet, whole {size:.0f} MB bag vs rosbags-dataframe: MB/s",
            "MB/s",
            size / ours.seconds,
            None if their_s is None else size / their_s,
            "-",
            None,
            "whole process; theirs: both topics one after the other, each in its own process",
        ),
        *_memory_rows(
            f"bag export -> Parquet, whole {size:.0f} MB bag vs rosbags-dataframe (/imu/data)",
            ours,
            theirs[0],
        ),
    ]


def bench_many_bags() -> list[Result]:
    """Many small bags: -j 2 beside -j 1, and the same export on a Dask LocalCluster."""
    bags = [str(p) for p in _small_bags()]
    python = _our_python()
    out = BUILD / "out-many"
    samples: dict[str, list[float]] = {"1": [], "2": []}
    argv = [*rostools_cmd(), "bag", "export", *bags, "-o", str(out), "--format", "parquet"]
    for _ in range(OUR_REPEATS):  # interleaved, so the load's drift hits both alike
        for jobs, got in samples.items():
            shutil.rmtree(out, ignore_errors=True)
            got.append(_measure([*argv, "-j", jobs]).wall)
    shutil.rmtree(out, ignore_errors=True)
    walls = {jobs: statistics.median(got) for jobs, got in samples.items()}
    note = (
        f"{len(bags)} bags of {SMALL_SECONDS} s (Imu 1 kHz, clouds 10 Hz), whole process, "
        f"median of {OUR_REPEATS} interleaved"
    )
    note += _load()
    results = [
        Result(
            f"bag export, {len(bags)} bags, -j 2 vs -j 1 (2 cores)",
            "s",
            walls["2"],
            walls["1"],
            "<= 0.7x -j 1",
            walls["2"] <= 0.7 * walls["1"],
            note,
        )
    ]
    try:
        dask = _measure([python, "-c", DASK_EXPORT, str(out), str(OUR_REPEATS), *bags]).reported()
    except RuntimeError as err:
        results.append(Result(
            f"bag export, {len(bags)} bags, Dask LocalCluster(2 workers) vs -j 2", "s", 0.0,
            walls["2"], "<= 1.5x -j 2", None, f"not measured: {str(err)[-200:]}",
        ))  # fmt: skip
        return results
    finally:
        shutil.rmtree(out, ignore_errors=True)
    rounds = [float(r) for r in dask["rounds"]]
    warm = statistics.median(rounds[1:]) if len(rounds) > 1 else rounds[0]
    results.append(Result(
        f"bag export, {len(bags)} bags, Dask LocalCluster(2 workers) vs -j 2", "s",
        rounds[0], walls["2"], "<= 1.5x -j 2", rounds[0] <= 1.5 * walls["2"],
        f"plan_export + client.map(export_bag) on workers fresh as -j's are, the cluster up "
        f"first (its start, {float(dask['cluster_start']):.1f} s, not counted); the same on "
        f"warm workers: {warm:.2f} s; -j 2 whole process, median of {OUR_REPEATS}",
    ))  # fmt: skip
    return results


BENCHMARKS = {
    "tables_topics": bench_topics,
    "tables_whole_bag": bench_whole_bag,
    "tables_many_bags": bench_many_bags,
}
