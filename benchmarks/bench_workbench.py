"""The bag workbench (issue 15): cat, merge and split, beside the rosbag Python API.

No ROS 1 tool cats, merges or splits; the closest is a short script over rosbag's Python API,
which is what people write. ``mcap cat``/``merge`` (the MCAP CLI) are not installable here.
Inputs are benchmarks/bench_bag.py's: the 1M-message bag (4 topics of std_msgs/String, about
80 MB) and the 10 s robot-like mix (about 330 MB of images and clouds).
"""

from __future__ import annotations

import os
import shutil
import statistics
import subprocess
import time

from benchmarks.bench_bag import BUILD, _mixed_bag, _small_bag
from benchmarks.common import SYSTEM_PYTHON, Result, have, rostools_cmd

RUNS = 3
OUT = BUILD / "workbench"

#: rosbag's nearest to ``bag cat``: decode each message and print it as one JSON line.
ROSBAG_CAT = r"""
import json, sys, rosbag
def plain(v):
    if hasattr(v, "__slots__"):
        return {k: plain(getattr(v, k)) for k in v.__slots__}
    if isinstance(v, (list, tuple)):
        return [plain(x) for x in v]
    if hasattr(v, "to_nsec"):
        return {"secs": v.secs, "nsecs": v.nsecs}
    return v
out = sys.stdout
for topic, msg, t in rosbag.Bag(sys.argv[1]).read_messages():
    out.write(json.dumps({"topic": topic, "type": msg._type, "log_time": t.to_nsec(),
                          "msg": plain(msg)}) + "\n")
"""
#: ... to ``bag cat --raw``: each message's bytes as base64 in one JSON line.
ROSBAG_CAT_RAW = r"""
import base64, json, sys, rosbag
out = sys.stdout
for topic, raw, t in rosbag.Bag(sys.argv[1]).read_messages(raw=True):
    out.write(json.dumps({"topic": topic, "type": raw[0], "log_time": t.to_nsec(),
                          "data": base64.b64encode(raw[1]).decode()}) + "\n")
"""
#: ... to ``bag merge``: read several bags raw, in time order, into one.
ROSBAG_MERGE = r"""
import heapq, sys, rosbag
bags = [rosbag.Bag(p) for p in sys.argv[2:]]
streams = [b.read_messages(raw=True, return_connection_header=True) for b in bags]
with rosbag.Bag(sys.argv[1], "w") as out:
    for topic, raw, t, header in heapq.merge(*streams, key=lambda m: m[2]):
        out.write(topic, raw, t, raw=True, connection_header=header)
"""
#: ... to ``bag split --duration``: a new bag every N seconds of bag time.
ROSBAG_SPLIT = r"""
import sys, rosbag
src, base, every = sys.argv[1], sys.argv[2], float(sys.argv[3])
inp = rosbag.Bag(src)
start = inp.get_start_time()
out, part = None, -1
for topic, raw, t, header in inp.read_messages(raw=True, return_connection_header=True):
    k = int((t.to_sec() - start) // every)
    if k != part:
        if out is not None:
            out.close()
        part = k
        out = rosbag.Bag("%s_%d.bag" % (base, part), "w")
    out.write(topic, raw, t, raw=True, connection_header=header)
out.close()
"""


def _clean() -> None:
    shutil.rmtree(OUT, ignore_errors=True)
    OUT.mkdir(parents=True)
    # The last run's writes are flushed now, not during the next run's timing.
    os.sync()


#: The peak RSS (MB) of the last process ``_seconds`` ran.
PEAK = [0.0]


def _seconds(argv: list[str], to_pipe: bool = False) -> tuple[float, int]:
    """Wall seconds of a whole process, and the lines it wrote to its stdout pipe."""
    start = time.perf_counter()
    proc = subprocess.Popen(argv, stdout=subprocess.PIPE if to_pipe else subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL)  # fmt: skip
    lines = 0
    if to_pipe:
        assert proc.stdout is not None
        while chunk := proc.stdout.read1(1 << 20):
            lines += chunk.count(b"\n")
    _, status, usage = os.wait4(proc.pid, 0)
    elapsed = time.perf_counter() - start
    PEAK[0] = usage.ru_maxrss / 1024
    if os.waitstatus_to_exitcode(status) != 0:
        raise RuntimeError(f"{' '.join(argv[:4])} failed")
    return elapsed, lines


def _pair(ours: list[str], theirs: list[str] | None, to_pipe: bool = False) -> tuple[
    list[tuple[float, int]], list[tuple[float, int]]
]:  # fmt: skip
    """RUNS runs of each, alternating; the output folder is emptied before each."""
    mine: list[tuple[float, int]] = []
    other: list[tuple[float, int]] = []
    for _ in range(RUNS):
        _clean()
        mine.append(_seconds(ours, to_pipe))
        if theirs is not None:
            _clean()
            other.append(_seconds(theirs, to_pipe))
    _clean()
    return mine, other


def bench_workbench() -> list[Result]:
    """cat of 1M small messages into a pipe; merge and split of the two bench bags."""
    small, mixed = _small_bag(), _mixed_bag()
    ros = have("rosbag")
    results: list[Result] = []

    mine, other = _pair(
        [*rostools_cmd(), "bag", "cat", str(small)],
        [SYSTEM_PYTHON, "-c", ROSBAG_CAT, str(small)] if ros else None,
        to_pipe=True,
    )
    rate = statistics.median(n / s for s, n in mine)
    their_rate = statistics.median(n / s for s, n in other) if other else None
    mb = small.stat().st_size / 1e6
    results.append(Result(
        "bag cat | pipe, 1M small messages (whole process)", "msgs/s", rate, their_rate,
        ">= 200000 msgs/s", rate >= 200_000,
        f"median of {RUNS}, {mb:.0f} MB: {mb * rate / 1e6:.1f} MB/s"
        + (f" vs {mb * their_rate / 1e6:.1f}" if their_rate else "")
        + "; theirs: rosbag Python API, read_messages + json.dumps per message",
    ))  # fmt: skip
    mine, other = _pair(
        [*rostools_cmd(), "bag", "split", str(small), "--duration", "100", "-o",
         str(OUT / "p.bag"), "-q"],
        [SYSTEM_PYTHON, "-c", ROSBAG_SPLIT, str(small), str(OUT / "t"), "100"] if ros else None,
    )  # fmt: skip
    results.append(_rate_row("bag split --duration 100, 1M small messages", mb, mine, other))

    size = (small.stat().st_size + mixed.stat().st_size) / 1e6
    mine, other = _pair(
        [*rostools_cmd(), "bag", "merge", str(OUT / "m.bag"), str(small), str(mixed), "-q"],
        [SYSTEM_PYTHON, "-c", ROSBAG_MERGE, str(OUT / "t.bag"), str(small), str(mixed)]
        if ros else None,
    )  # fmt: skip
    results.append(_rate_row("bag merge, 1M-message bag + robot mix -> .bag", size, mine, other))

    size = mixed.stat().st_size / 1e6
    mine, other = _pair(
        [*rostools_cmd(), "bag", "split", str(mixed), "--duration", "1", "-o",
         str(OUT / "p.bag"), "-q"],
        [SYSTEM_PYTHON, "-c", ROSBAG_SPLIT, str(mixed), str(OUT / "t"), "1"] if ros else None,
    )  # fmt: skip
    results.append(_rate_row("bag split --duration 1, robot mix (10 parts)", size, mine, other))
    return results


def _rate_row(
    name: str, size_mb: float, mine: list[tuple[float, int]], other: list[tuple[float, int]]
) -> Result:
    rate = size_mb / statistics.median(s for s, _ in mine)
    their_rate = size_mb / statistics.median(s for s, _ in other) if other else None
    return Result(
        name, "MB/s", rate, their_rate, "report (more is better)", None,
        f"input {size_mb:.0f} MB, whole process, median of {RUNS}; theirs: a rosbag Python API "
        "script doing the same (no ROS 1 tool does)",
    )  # fmt: skip


BIG_SECONDS = 60  # of the robot-like mix: about 2 GB


def bench_workbench_2gb() -> list[Result]:
    """A 2 GB bag split into 10 s parts and the parts merged back: MB/s, and our peak RSS."""
    big = _mixed_bag(BIG_SECONDS)
    size = big.stat().st_size / 1e6
    ros = have("rosbag")
    times: dict[str, list[float]] = {
        key: [] for key in ("split", "merge", "cat", "their split", "their merge", "their cat")
    }
    peaks: list[float] = []
    for _ in range(RUNS):
        _clean()
        times["cat"].append(_seconds([*rostools_cmd(), "bag", "cat", "--raw", str(big)], True)[0])
        peaks.append(PEAK[0])
        if ros:
            cat = [SYSTEM_PYTHON, "-c", ROSBAG_CAT_RAW, str(big)]
            times["their cat"].append(_seconds(cat, True)[0])
        split = [*rostools_cmd(), "bag", "split", str(big), "--duration", "10", "-o",
                 str(OUT / "p.bag"), "-q"]  # fmt: skip
        times["split"].append(_seconds(split)[0])
        peaks.append(PEAK[0])
        parts = sorted(OUT.glob("p_*.bag"))
        merge = [*rostools_cmd(), "bag", "merge", str(OUT / "m.bag"), *map(str, parts), "-q"]
        times["merge"].append(_seconds(merge)[0])
        peaks.append(PEAK[0])
        if ros:
            _clean()
            split = [SYSTEM_PYTHON, "-c", ROSBAG_SPLIT, str(big), str(OUT / "t"), "10"]
            times["their split"].append(_seconds(split)[0])
            parts = sorted(OUT.glob("t_*.bag"))
            merge = [SYSTEM_PYTHON, "-c", ROSBAG_MERGE, str(OUT / "m.bag"), *map(str, parts)]
            times["their merge"].append(_seconds(merge)[0])
    _clean()

    def rate(key: str) -> float | None:
        return size / statistics.median(times[key]) if times[key] else None

    note = (f"{size:.0f} MB robot-like mix, whole process, median of {RUNS}; our peak RSS "
            f"{max(peaks):.0f} MB; theirs: rosbag Python API scripts")  # fmt: skip
    return [
        Result("bag split --duration 10, 2 GB bag", "MB/s", rate("split") or 0.0,
               rate("their split"), "report (memory flat)", None, note),
        Result("bag merge of its 6 parts back, 2 GB", "MB/s", rate("merge") or 0.0,
               rate("their merge"), "report (memory flat)", None, note),
        Result("bag cat --raw | pipe, 2 GB bag", "MB/s", rate("cat") or 0.0,
               rate("their cat"), "report (memory flat)", None,
               note.replace("scripts", "read_messages(raw=True) + base64 + json.dumps")),
    ]  # fmt: skip


BENCHMARKS = {"workbench": bench_workbench, "workbench_2gb": bench_workbench_2gb}
