"""``topic plot`` at 1 and 10 kHz, and ``bag plot`` over a 1M-message bag (issue 16).

ROS 1 plots with rqt_plot, a GUI that is not installed here (and needs a display). What ROS 1
offers from the command line is ``rostopic echo -p`` of the same field, the CSV rqt_plot's
users pipe into a spreadsheet or gnuplot; that is the comparison. For bags there is no tool
at all: the comparison is a rosbag Python API script that extracts the same fields.

- live: a roscpp ``pub_rate`` sends 16-pixel ``sensor_msgs/Image`` messages at 1 and 10 kHz
  for 5 s; ``topic plot /bench/width`` runs in a pseudo-terminal (so it redraws live, at
  10 Hz) and ``rostopic echo -p /bench/width`` into a pipe. Reported: CPU seconds of the
  whole process, and the messages each took in against those published.
- bag: the 1M-message bag of bench_bag.py is std_msgs/String, which has no number to plot;
  its twin here holds 1M ``geometry_msgs/PointStamped`` on 4 topics (about 90 MB).
  ``bag plot`` of ``point/x`` on all four, terminal frame into a pipe, against the script.
"""

from __future__ import annotations

import fcntl
import os
import pty
import re
import signal
import statistics
import struct
import subprocess
import termios
import threading
import time

from benchmarks.bench_bag import BUILD
from benchmarks.bench_topic_cpp import RUN, _publisher, _wait_json
from benchmarks.bench_workbench import PEAK, _seconds
from benchmarks.common import SYSTEM_PYTHON, Result, have, master, ros_env, rostools_cmd, start

POINT_BAG = BUILD / "points-1m.bag"
RUNS = 3
ANSI = re.compile(rb"\x1b\[[0-9;?]*[A-Za-z]")

#: rosbag's nearest to ``bag plot``: every (time, value) of the fields, into lists.
ROSBAG_PLOT = r"""
import sys, rosbag
series = {}
for topic, msg, t in rosbag.Bag(sys.argv[1]).read_messages(topics=sys.argv[2:]):
    series.setdefault(topic, []).append((t.to_sec(), msg.point.x))
print(sum(len(v) for v in series.values()))
"""


def _in_pty(argv: list[str], env: dict[str, str]) -> tuple[subprocess.Popen[bytes], list[bytes]]:
    """Start ``argv`` on a 30x100 pseudo-terminal; its output gathers in the list."""
    leader, follower = pty.openpty()
    fcntl.ioctl(follower, termios.TIOCSWINSZ, struct.pack("HHHH", 30, 100, 0, 0))
    proc = subprocess.Popen(
        argv, env={**env, "TERM": "xterm-256color"}, stdin=follower, stdout=follower,
        stderr=follower, start_new_session=True,
    )  # fmt: skip
    os.close(follower)
    chunks: list[bytes] = []

    def drain() -> None:
        while True:
            try:
                data = os.read(leader, 1 << 16)
            except OSError:
                break
            if not data:
                break
            chunks.append(data)
        os.close(leader)

    threading.Thread(target=drain, daemon=True).start()
    return proc, chunks


def _plot_ours(rate: float, env: dict[str, str]) -> tuple[float, int, int, int]:
    """(CPU s, messages plotted, messages published, frames drawn) of one live run."""
    tool, chunks = _in_pty(
        [*rostools_cmd(), "topic", "plot", "/bench/width", "--timeout", str(RUN + 4)], env
    )
    pub = _publisher(rate, 16, "sensor_msgs/Image", env)
    truth = _wait_json(pub, RUN + 30)
    cpu = _cpu_when_done(tool, RUN + 30)
    time.sleep(0.2)  # the last bytes through the terminal
    screen = b"".join(chunks)
    counts = re.findall(rb"([0-9,]+) messages, [0-9,]+/s", ANSI.sub(b"", screen))
    plotted = int(counts[-1].replace(b",", b"")) if counts else 0
    return cpu, plotted, int(truth["published"]), screen.count(b"\x1b[H")


def _cpu_when_done(proc: subprocess.Popen[bytes], timeout: float) -> float:
    """CPU seconds (user + system) of ``proc`` once it exits (SIGINT after ``timeout``)."""
    deadline = time.monotonic() + timeout
    while True:
        pid, _, usage = os.wait4(proc.pid, os.WNOHANG)
        if pid == proc.pid:
            proc.returncode = 0  # reaped here: Popen must not wait for it again
            return float(usage.ru_utime + usage.ru_stime)
        if time.monotonic() > deadline:
            os.killpg(proc.pid, signal.SIGINT)
            deadline = time.monotonic() + 10
        time.sleep(0.05)


def _echo_theirs(rate: float, env: dict[str, str]) -> tuple[float, int, int]:
    """(CPU s, rows printed, messages published) of ``rostopic echo -p`` into a pipe."""
    tool = start(
        ["rostopic", "echo", "-p", "/bench/width"], env, stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
    )  # fmt: skip
    assert tool.stdout is not None
    stdout = tool.stdout
    rows = [0]

    def drain() -> None:  # a reader that never holds the writer back (a full pipe would)
        while chunk := stdout.read1(1 << 16):
            rows[0] += chunk.count(b"\n")

    reader = threading.Thread(target=drain)
    reader.start()
    pub = _publisher(rate, 16, "sensor_msgs/Image", env)
    truth = _wait_json(pub, RUN + 30)
    time.sleep(1.5)
    os.killpg(tool.pid, signal.SIGINT)
    cpu = _cpu_when_done(tool, 20)
    reader.join()
    return cpu, rows[0] - 1, int(truth["published"])  # less the %time,field header


def bench_topic_plot() -> list[Result]:
    """CPU of a live plot at 1 and 10 kHz beside rostopic echo -p; median of RUNS runs."""
    results: list[Result] = []
    with master() as uri:
        env = ros_env(uri)
        for rate in (1000.0, 10000.0):
            ours = [_plot_ours(rate, env) for _ in range(RUNS)]
            theirs = [_echo_theirs(rate, env) for _ in range(RUNS)] if have("rostopic") else []
            cpu = statistics.median(r[0] for r in ours)
            other = statistics.median(r[0] for r in theirs) if theirs else None
            kept = min(r[1] / r[2] for r in ours)
            their_kept = min(r[1] / r[2] for r in theirs) if theirs else None
            frames = statistics.median(r[3] for r in ours)
            results.append(Result(
                f"topic plot CPU at {rate / 1000:g} kHz, {RUN:g} s (live, in a terminal)", "s",
                cpu, other, "report; keeps every message", kept >= 0.999,
                f"whole process, median of {RUNS}; ours plotted {kept:.1%} of the messages "
                f"(worst run) in {frames:.0f} frames; theirs: rostopic echo -p of the same "
                "field into a pipe (rqt_plot is a GUI, not installed)"
                + ("" if their_kept is None else f", which printed {their_kept:.1%}"),
            ))  # fmt: skip
    return results


def _point_bag() -> os.PathLike[str]:
    """1,000,000 geometry_msgs/PointStamped on 4 topics (x = i, stamped), frame_id 'map'."""
    if POINT_BAG.exists():
        return POINT_BAG
    from rostools.bag.formats.access import open_writer
    from rostools.msgs.store import TypeStore

    store = TypeStore.default()
    kind = "geometry_msgs/PointStamped"
    BUILD.mkdir(parents=True, exist_ok=True)
    tmp = POINT_BAG.with_suffix(".tmp")
    tmp.unlink(missing_ok=True)
    writer = open_writer(tmp, format="bag")
    conns = [
        writer.add_connection(f"/point{i}", kind, store.md5(kind), store.full_text(kind),
                              callerid=f"/pointer{i}")
        for i in range(4)
    ]  # fmt: skip
    head = struct.Struct("<III")
    tail = b"\x03\x00\x00\x00map"
    body = struct.Struct("<3d")
    t0 = 1_700_000_000_000_000_000
    for i in range(1_000_000):
        t = t0 + i * 1_000_000
        data = head.pack(i, t // 10**9, t % 10**9) + tail + body.pack(i, -i, i / 7)
        writer.write(conns[i & 3], t, data)
    writer.close()
    tmp.rename(POINT_BAG)
    return POINT_BAG


def bench_bag_plot() -> Result:
    """``bag plot`` of point/x on 4 topics of 1M messages, beside a rosbag API script."""
    bag = _point_bag()
    size = os.path.getsize(bag) / 1e6
    topics = [f"/point{i}" for i in range(4)]
    ours = [*rostools_cmd(), "bag", "plot", str(bag), *(f"{t}/point/x" for t in topics)]
    theirs = [SYSTEM_PYTHON, "-c", ROSBAG_PLOT, str(bag), *topics]
    mine: list[float] = []
    other: list[float] = []
    peaks: list[float] = []
    for _ in range(RUNS):
        mine.append(_seconds(ours, to_pipe=True)[0])
        peaks.append(PEAK[0])
        if have("rosbag"):
            other.append(_seconds(theirs, to_pipe=True)[0])
    rate = size / statistics.median(mine)
    their_rate = size / statistics.median(other) if other else None
    return Result(
        "bag plot, 1M PointStamped on 4 topics -> terminal frame", "MB/s", rate, their_rate,
        "report (more is better)", None,
        f"input {size:.0f} MB, whole process, median of {RUNS}; our peak RSS {max(peaks):.0f} MB; "
        "theirs: rosbag Python API script collecting (t, point.x) per topic (no ROS 1 tool "
        "plots a bag)",
    )  # fmt: skip


BENCHMARKS = {"topic_plot": bench_topic_plot, "bag_plot": bench_bag_plot}
