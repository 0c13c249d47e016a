"""``bag convert --to ros2`` beside ``rosbags-convert``, in one run, on the same bags.

Two ROS 1 bags are generated once into benchmarks/build/ros2/ (gitignored), of about
``ROSTOOLS_BENCH_ROS2_MB`` MB each (default 1000; 100 for development):

- ``small``: robot-like small messages, std_msgs/String, sensor_msgs/Imu and
  tf2_msgs/TFMessage (two transforms), about 220 bytes each, 4.5 million a GB;
- ``images``: sensor_msgs/Image, 640 x 480 rgb8 (900 KB each), about 1,100 a GB.

Each is converted to a rosbag2 folder with one MCAP by ``rostools bag convert IN OUT --to
ros2 --distro D -c none`` and by ``rosbags-convert --src IN --dst OUT --dst-storage mcap
--dst-typestore ros2_D`` (its message conversion, which drops ``seq``, as ours does; its MCAP
chunks are not compressed, hence ``-c none``), D the same distro for both
(``ROSTOOLS_BENCH_ROS2_DISTRO``, default: ours); and by ours again with its default zstd
chunks, beside the same rosbags-convert figure. Reported, per bag:
messages per second over the whole process's wall time (start-up included), and each
process's peak resident memory as the kernel counts it for a reaped child (``wait4``'s
``ru_maxrss``: the process and any children it waited for). The input is read once before
the runs so both find it in the page cache; each output is checked for the message count, then
deleted; ``ROSTOOLS_BENCH_ROS2_OUT`` puts the outputs elsewhere (a tmpfs, to take the disk's
write speed out of the figures). ``ROSTOOLS_BENCH_ROS2_RUNS`` runs each (default 1; the median
is reported). Each note gives both processes' CPU seconds beside their wall time. A plain
``cp`` of the input to the same place, timed the same way, is the floor beside each bag.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import statistics
import struct
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from benchmarks.common import ROOT, Result, rostools_cmd

BUILD = ROOT / "benchmarks" / "build" / "ros2"
#: Goal of issue 39: at least this many times rosbags-convert's messages per second.
SPEED_GOAL = 5.0
T0 = 1_700_000_000_000_000_000
IMAGE_SHAPE = (480, 640, 3)


def _size_mb() -> int:
    return int(os.environ.get("ROSTOOLS_BENCH_ROS2_MB", "1000"))


def _runs() -> int:
    return max(1, int(os.environ.get("ROSTOOLS_BENCH_ROS2_RUNS", "1")))


def _distro() -> str:
    """The distro both converters target: the env's, else our default."""
    if given := os.environ.get("ROSTOOLS_BENCH_ROS2_DISTRO"):
        return given
    code = "from rostools.bag.formats.ros2types import DEFAULT_DISTRO; print(DEFAULT_DISTRO)"
    python = str(Path(rostools_cmd()[0]).parent / "python")
    return subprocess.run(
        [python, "-c", code], capture_output=True, text=True, check=True
    ).stdout.strip()


def _rosbags_convert() -> str:
    """rosbags-convert of the interpreter running the benchmarks (the project's venv)."""
    beside = Path(sys.executable).parent / "rosbags-convert"
    found = str(beside) if beside.exists() else shutil.which("rosbags-convert")
    if found is None:
        raise RuntimeError("rosbags-convert is not installed (pip install rosbags==0.11.*)")
    return found


# --- the input bags ---------------------------------------------------------------------------


def _string(text: bytes) -> bytes:
    return struct.pack("<I", len(text)) + text


def _header(seq: int, t_ns: int, frame: bytes) -> bytes:
    return struct.pack("<3I", seq, t_ns // 1_000_000_000, t_ns % 1_000_000_000) + _string(frame)


def _imu(i: int, t_ns: int) -> bytes:
    cov = (0.01, 0.0, 0.0, 0.0, 0.01, 0.0, 0.0, 0.0, 0.01)
    return _header(i, t_ns, b"imu_link") + struct.pack(
        "<37d", 0.0, 0.0, 0.1 * (i % 7), 0.99, *cov, 0.01 * i, 0.02, 0.03, *cov,
        0.1, 0.2, 9.81, *cov,
    )  # fmt: skip


def _tf(i: int, t_ns: int) -> bytes:
    parts = [struct.pack("<I", 2)]
    for parent, child in ((b"odom", b"base_link"), (b"base_link", b"laser")):
        parts.append(_header(i, t_ns, parent) + _string(child))
        parts.append(struct.pack("<7d", 0.001 * i, 2.0, 0.0, 0.0, 0.0, 0.0, 1.0))
    return b"".join(parts)


def _chatter(i: int, t_ns: int) -> bytes:
    return _string(b"hello world %d" % i)


def _image_frames() -> list[bytes]:
    """Eight camera-like frames: a gradient plus noise (as bench_bag's)."""
    import numpy as np

    rng = np.random.default_rng(1)
    h, w, c = IMAGE_SHAPE
    ramp = np.add.outer(np.arange(h), np.arange(w * c) // c).astype(np.uint8)
    return [(ramp + rng.integers(0, 24, ramp.shape, dtype=np.uint8)).tobytes() for _ in range(8)]


@dataclass(frozen=True)
class Stream:
    """One topic of a generated bag: its rate and how its i-th message is made."""

    topic: str
    type: str
    hz: int
    make: Callable[[int, int], bytes]


def _image_stream() -> Stream:
    frames = _image_frames()
    h, w, c = IMAGE_SHAPE

    def make(i: int, t_ns: int) -> bytes:
        meta = _header(i, t_ns, b"camera") + struct.pack("<II", h, w) + _string(b"rgb8")
        return meta + struct.pack("<BII", 0, w * c, h * w * c) + frames[i % len(frames)]

    return Stream("/camera/image_raw", "sensor_msgs/Image", 30, make)


def _streams(kind: str) -> list[Stream]:
    if kind == "images":
        return [_image_stream()]
    return [
        Stream("/imu/data", "sensor_msgs/Imu", 200, _imu),
        Stream("/tf", "tf2_msgs/TFMessage", 100, _tf),
        Stream("/chatter", "std_msgs/String", 100, _chatter),
    ]


def _bag(kind: str) -> tuple[Path, int]:
    """The generated bag of ``kind`` (``small`` or ``images``) and its message count."""
    size = _size_mb() * 1_000_000
    path = BUILD / f"{kind}-{_size_mb()}mb.bag"
    count_file = path.with_suffix(".json")
    if path.exists() and count_file.exists():
        return path, int(json.loads(count_file.read_text())["messages"])
    from rostools.bag.formats.access import open_writer
    from rostools.msgs.store import TypeStore

    BUILD.mkdir(parents=True, exist_ok=True)
    store = TypeStore.default()
    streams = _streams(kind)
    tmp = path.with_suffix(".tmp")
    tmp.unlink(missing_ok=True)
    writer = open_writer(tmp, format="bag")
    conns = [
        writer.add_connection(
            s.topic, s.type, store.md5(s.type), store.full_text(s.type), callerid="/robot"
        )
        for s in streams
    ]
    # One tick of the slowest common rate; each stream writes its share in time order.
    base = min(s.hz for s in streams)
    per_tick = [s.hz // base for s in streams]
    written = messages = 0
    tick = 0
    while written < size:
        for k, (stream, n) in enumerate(zip(streams, per_tick, strict=True)):
            for j in range(n):
                i = tick * n + j
                t_ns = T0 + i * 1_000_000_000 // stream.hz + k
                data = stream.make(i, t_ns)
                writer.write(conns[k], t_ns, data)
                written += len(data) + 30
                messages += 1
        tick += 1
    writer.close()
    tmp.rename(path)
    count_file.write_text(json.dumps({"messages": messages}))
    return path, messages


# --- the runs ---------------------------------------------------------------------------------


@dataclass
class Run:
    """One converter's run: wall seconds, peak resident memory in kB, CPU seconds."""

    seconds: float
    peak_kb: int
    cpu: float


def _run(argv: Sequence[str]) -> Run:
    """Run ``argv`` to its end; its wall time and the peak RSS ``wait4`` reports for it."""
    start = time.perf_counter()
    proc = subprocess.Popen(
        list(argv), stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE
    )
    assert proc.stderr is not None
    err = proc.stderr.read()  # to its end: a full pipe would stall the child
    _, status, usage = os.wait4(proc.pid, 0)
    elapsed = time.perf_counter() - start
    proc.returncode = os.waitstatus_to_exitcode(status)  # reaped here, not by Popen
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(argv)} failed ({proc.returncode}): {err.decode()[-800:]}")
    return Run(elapsed, usage.ru_maxrss, usage.ru_utime + usage.ru_stime)


def _message_count(folder: Path) -> int:
    """The bag's message count from its metadata.yaml (the first, the bag's own)."""
    text = (folder / "metadata.yaml").read_text()
    found = re.search(r"^  message_count:\s*(\d+)", text, re.M)
    if found is None:
        raise RuntimeError(f"no message_count in {folder}/metadata.yaml")
    return int(found.group(1))


def _converted(argv: Sequence[str], out: Path, messages: int) -> Run:
    shutil.rmtree(out, ignore_errors=True)
    try:
        run = _run(argv)
        got = _message_count(out)
        if got != messages:
            raise RuntimeError(f"{argv[0]} wrote {got} messages of {messages}")
        return run
    finally:
        shutil.rmtree(out, ignore_errors=True)


def _copied(src: Path, dst: Path) -> Run:
    """A plain ``cp`` of the input to where the outputs go: what copying the bytes costs."""
    dst.unlink(missing_ok=True)
    try:
        return _run(["cp", str(src), str(dst)])
    finally:
        dst.unlink(missing_ok=True)


def _warm(path: Path) -> None:
    """Read the input once, so that neither converter pays for the disk and the other not."""
    with path.open("rb") as f:
        while f.read(16 * 1024 * 1024):
            pass


def _median(runs: list[Run]) -> Run:
    return Run(
        statistics.median(r.seconds for r in runs),
        int(statistics.median(r.peak_kb for r in runs)),
        statistics.median(r.cpu for r in runs),
    )


def _out_dir() -> Path:
    """Where the outputs go: ``ROSTOOLS_BENCH_ROS2_OUT`` (a tmpfs takes the disk out of the
    figures: 1 GB of images is written as fast as this disk takes it, by either), else BUILD."""
    given = os.environ.get("ROSTOOLS_BENCH_ROS2_OUT")
    return Path(given) if given else BUILD


def _compare(kind: str, label: str) -> list[Result]:
    bag, messages = _bag(kind)
    distro = _distro()
    ours_out, theirs_out = _out_dir() / "out-ours", _out_dir() / "out-rosbags"
    ours_argv = [*rostools_cmd(), "bag", "convert", str(bag), str(ours_out), "--to", "ros2",
                 "--distro", distro, "-q"]  # fmt: skip
    theirs_argv = [_rosbags_convert(), "--src", str(bag), "--dst", str(theirs_out),
                   "--dst-storage", "mcap", "--dst-typestore", f"ros2_{distro}"]  # fmt: skip
    _warm(bag)
    ours_runs, zstd_runs, theirs_runs, cp_runs = [], [], [], []
    for _ in range(_runs()):  # interleaved, so that drift hits both alike
        ours_runs.append(_converted([*ours_argv, "-c", "none"], ours_out, messages))
        theirs_runs.append(_converted(theirs_argv, theirs_out, messages))
        zstd_runs.append(_converted(ours_argv, ours_out, messages))
        cp_runs.append(_copied(bag, _out_dir() / "out-cp.bag"))
    ours, zstd, theirs = _median(ours_runs), _median(zstd_runs), _median(theirs_runs)
    cp = _median(cp_runs)
    size_mb = bag.stat().st_size / 1e6
    where = "tmpfs" if os.environ.get("ROSTOOLS_BENCH_ROS2_OUT") else "disk"
    note = (
        f"{messages:,} messages, {size_mb:,.0f} MB, distro {distro}; output to {where}; whole "
        f"process, median of {_runs()}; theirs: rosbags-convert --dst-storage mcap "
        f"--dst-typestore ros2_{distro} (its MCAP chunks are not compressed)"
    )
    rate, zstd_rate, their_rate = (messages / r.seconds for r in (ours, zstd, theirs))
    target = f">= {SPEED_GOAL:g}x rosbags-convert"
    return [
        Result(
            f"bag convert --to ros2 -c none, {label}",
            "msgs/s",
            rate,
            their_rate,
            target,
            rate >= SPEED_GOAL * their_rate,
            note + f"; {ours.seconds:.1f} s ({ours.cpu:.1f} s CPU) vs {theirs.seconds:.1f} s "
            f"({theirs.cpu:.1f} s CPU)",
        ),
        Result(
            f"bag convert --to ros2 (zstd, the default), {label}",
            "msgs/s",
            zstd_rate,
            their_rate,
            target,
            zstd_rate >= SPEED_GOAL * their_rate,
            note + f"; ours compresses its chunks: {zstd.seconds:.1f} s ({zstd.cpu:.1f} s CPU) vs "
            f"{theirs.seconds:.1f} s ({theirs.cpu:.1f} s CPU)",
        ),
        Result(
            f"bag convert --to ros2 -c none, {label}, beside cp",
            "msgs/s",
            rate,
            messages / cp.seconds,
            "the floor: cp of the input to the same place",
            None,
            note + f"; ours {ours.seconds:.2f} s ({ours.cpu:.2f} s CPU), cp {cp.seconds:.2f} s "
            f"({cp.cpu:.2f} s CPU), rosbags-convert {theirs.seconds:.2f} s ({theirs.cpu:.2f} s "
            "CPU); the messages/s cp's time would give",
        ),
        Result(
            f"bag convert --to ros2 -c none, {label}, peak RSS",
            "MB",
            ours.peak_kb / 1024,
            theirs.peak_kb / 1024,
            "<= rosbags-convert",
            ours.peak_kb <= theirs.peak_kb,
            f"ru_maxrss of the reaped process (wait4); zstd: {zstd.peak_kb / 1024:.0f} MB; " + note,
        ),
    ]


def bench_ros2_small() -> list[Result]:
    return _compare("small", f"{_size_mb()} MB of small messages (String, Imu, TF)")


def bench_ros2_images() -> list[Result]:
    return _compare("images", f"{_size_mb()} MB of 640x480 images")


BENCHMARKS = {
    "ros2_convert_small": bench_ros2_small,
    "ros2_convert_images": bench_ros2_images,
}
