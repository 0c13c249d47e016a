"""Bags: ``info`` on a 1M-message bag, and .bag -> MCAP conversion throughput.

The input bags are written once with our writer into benchmarks/build/ (gitignored).
"""

from __future__ import annotations

import statistics
import subprocess
from pathlib import Path

from benchmarks.common import ROOT, SYSTEM_PYTHON, Result, have, rostools_cmd, time_commands

BUILD = ROOT / "benchmarks" / "build"
SMALL_BAG = BUILD / "small-1m.bag"
MIXED_BAG = BUILD / "mixed.bag"
#: Seconds of recording in the mixed bag: camera 30 Hz, lidar 10 Hz, imu 200 Hz, odom 50 Hz,
#: tf 100 Hz, about 33 MB per second, nearly all of it images and point clouds.
MIXED_SECONDS = 10
REPEATS = 3

# rosbag has no converter; the closest is a raw copy through its Python API (what rosbag
# filter does, without deserializing), bag -> bag with the connection headers kept.
ROSBAG_COPY = r"""
import sys, time, rosbag
src, dst = sys.argv[1], sys.argv[2]
start = time.perf_counter()
with rosbag.Bag(src) as inp, rosbag.Bag(dst, "w") as out:
    for topic, raw, t, header in inp.read_messages(raw=True, return_connection_header=True):
        out.write(topic, raw, t, raw=True, connection_header=header)
print(time.perf_counter() - start)
"""


def _python() -> str:
    """The benchmark venv's interpreter (a normal install of rostools)."""
    return str(Path(rostools_cmd()[0]).parent / "python")


def _small_bag() -> Path:
    """1,000,000 std_msgs/String messages on 4 topics (about 80 MB)."""
    if SMALL_BAG.exists():
        return SMALL_BAG
    import struct

    from rostools.bag.formats.access import open_writer

    BUILD.mkdir(parents=True, exist_ok=True)
    tmp = SMALL_BAG.with_suffix(".tmp")
    tmp.unlink(missing_ok=True)
    writer = open_writer(tmp, format="bag")
    conns = [
        writer.add_connection(
            f"/chatter{i}",
            "std_msgs/String",
            "992ce8a1687cec8c8bd883ec73ca41d1",
            "string data\n",
            callerid=f"/talker{i}",
        )
        for i in range(4)
    ]
    for i in range(1_000_000):
        text = b"hello world %d" % i
        writer.write(
            conns[i & 3],
            1_700_000_000_000_000_000 + i * 1_000_000,
            struct.pack("<I", len(text)) + text,
        )
    writer.close()
    tmp.rename(SMALL_BAG)
    return SMALL_BAG


def _mixed_bag(seconds: int = MIXED_SECONDS) -> Path:
    """A robot-like recording: images and clouds carry the bytes, small messages the count."""
    path = MIXED_BAG if seconds == MIXED_SECONDS else BUILD / f"mixed-{seconds}s.bag"
    if path.exists():
        return path
    import numpy as np

    from rostools.bag.formats.access import open_writer

    BUILD.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(1)
    # Camera-like: a smooth gradient plus sensor noise (compresses, but not to nothing).
    ramp = np.add.outer(np.arange(480), np.arange(640 * 3) // 3).astype(np.uint8)
    images = [(ramp + rng.integers(0, 24, ramp.shape, dtype=np.uint8)).tobytes() for _ in range(8)]
    clouds = [rng.normal(0, 20, 16384 * 8).astype(np.float32).tobytes() for _ in range(8)]
    small = {"imu": rng.bytes(324), "odom": rng.bytes(725), "tf": rng.bytes(140)}
    tmp = path.with_suffix(".tmp")
    tmp.unlink(missing_ok=True)
    writer = open_writer(tmp, format="bag")

    def conn(topic: str, kind: str, md5: str) -> object:
        return writer.add_connection(topic, kind, md5, "", callerid="/robot")

    streams = [
        (
            30,
            conn("/camera/image_raw", "sensor_msgs/Image", "060021388200f6f0f447d0fcd9c64743"),
            images,
        ),
        (
            10,
            conn("/velodyne_points", "sensor_msgs/PointCloud2", "1158d486dd51d683ce2f1be655c3c181"),
            clouds,
        ),
        (
            200,
            conn("/imu/data", "sensor_msgs/Imu", "6a62c6daae103f4ff57a132d6f95cec2"),
            [small["imu"]],
        ),
        (
            50,
            conn("/odom", "nav_msgs/Odometry", "cd5e73d190d741a2f92e81eda573aca7"),
            [small["odom"]],
        ),
        (100, conn("/tf", "tf2_msgs/TFMessage", "94810edda583a504dfda3829e70d7eec"), [small["tf"]]),
    ]
    events = []
    for k, (hz, c, payloads) in enumerate(streams):
        for i in range(hz * seconds):
            events.append((i * 1_000_000_000 // hz + k, c, payloads[i % len(payloads)]))
    events.sort(key=lambda e: e[0])
    for t, c, data in events:
        writer.write(c, 1_700_000_000_000_000_000 + t, data)  # type: ignore[arg-type]
    writer.close()
    tmp.rename(path)
    return path


def bench_info() -> Result:
    bag = _small_bag()
    ours = [*rostools_cmd(), "bag", "info", str(bag)]
    name = "bag info, 1M-message bag (wall, whole process)"
    note = "rostools bag info FILE vs rosbag info FILE, median of 10, interpreter start included"
    if not have("rosbag"):
        t = time_commands({"ours": ours}, runs=10, warmup=2)
        return Result(name, "ms", t["ours"] * 1e3, None, "<= 0.5x rosbag info", None, note)
    t = time_commands({"ours": ours, "theirs": ["rosbag", "info", str(bag)]}, runs=10, warmup=2)
    ratio = t["ours"] / t["theirs"]
    return Result(
        name, "ms", t["ours"] * 1e3, t["theirs"] * 1e3, "<= 0.5x rosbag info", ratio <= 0.5, note
    )


def _convert_seconds(src: Path, compression: str) -> float:
    """Median wall time of ``convert(src, x.mcap)`` in a fresh process, output deleted after."""
    out = BUILD / "out.mcap"
    code = (
        "import sys, time; from rostools.bag.tools.ops import convert; "
        "from rostools.bag.tools.options import CopyOptions; s = time.perf_counter(); "
        "convert(sys.argv[1], sys.argv[2], CopyOptions(compression=sys.argv[3], overwrite=True)); "
        "print(time.perf_counter() - s)"
    )
    samples = []
    for _ in range(REPEATS):
        proc = subprocess.run(
            [_python(), "-c", code, str(src), str(out), compression],
            capture_output=True,
            text=True,
            check=True,
        )
        samples.append(float(proc.stdout))
        out.unlink()
    return statistics.median(samples)


def _rosbag_copy_seconds(src: Path) -> float | None:
    if not have("rosbag"):
        return None
    out = BUILD / "out-rosbag.bag"
    samples = []
    for _ in range(REPEATS):
        proc = subprocess.run(
            [SYSTEM_PYTHON, "-c", ROSBAG_COPY, str(src), str(out)],
            capture_output=True,
            text=True,
            check=True,
        )
        samples.append(float(proc.stdout))
        out.unlink()
    return statistics.median(samples)


def _convert_results(src: Path, label: str, compressions: list[str]) -> list[Result]:
    size_mb = src.stat().st_size / 1e6
    theirs = _rosbag_copy_seconds(src)
    their_rate = size_mb / theirs if theirs else None
    results = []
    for compression in compressions:
        rate = size_mb / _convert_seconds(src, compression)
        results.append(
            Result(
                f"convert .bag -> MCAP ({compression}), {label}",
                "MB/s",
                rate,
                their_rate,
                ">= 200 MB/s",
                rate >= 200,
                "theirs: rosbag Python API raw copy .bag -> .bag (no converter exists); "
                f"input {size_mb:.0f} MB, median of {REPEATS}, disk-bound when uncompressed",
            )
        )
    return results


def bench_convert() -> list[Result]:
    return _convert_results(
        _mixed_bag(), f"{MIXED_SECONDS} s robot-like mix", ["none", "lz4", "zstd"]
    )


def bench_convert_small() -> list[Result]:
    return _convert_results(_small_bag(), "1M small messages", ["lz4"])


ROSBAG_READ = r"""
import sys, time, rosbag
start = time.perf_counter()
n = sum(1 for _ in rosbag.Bag(sys.argv[1]).read_messages(raw=True))
print(n / (time.perf_counter() - start))
"""

OUR_READ = r"""
import sys, time
from rostools.bag.formats.access import open_bag
start = time.perf_counter()
with open_bag(sys.argv[1]) as reader:
    n = sum(1 for _ in reader.messages())
print(n / (time.perf_counter() - start))
"""


def bench_read() -> Result:
    bag = _small_bag()
    ours = statistics.median(
        float(
            subprocess.run(
                [_python(), "-c", OUR_READ, str(bag)], capture_output=True, text=True, check=True
            ).stdout
        )
        for _ in range(REPEATS)
    )
    theirs = None
    if have("rosbag"):
        proc = subprocess.run(
            [SYSTEM_PYTHON, "-c", ROSBAG_READ, str(bag)], capture_output=True, text=True, check=True
        )
        theirs = float(proc.stdout)
    return Result(
        "read raw messages in time order, 1M small messages",
        "msgs/s",
        ours,
        theirs,
        "faster than rosbag.Bag",
        None if theirs is None else ours > theirs,
        "open + messages() vs rosbag.Bag(...).read_messages(raw=True), in-process time",
    )


BENCHMARKS = {
    "bag_info": bench_info,
    "bag_read": bench_read,
    "bag_convert": bench_convert,
    "bag_convert_small": bench_convert_small,
}
