"""``rostools tf echo`` beside the real tools, in one run.

- ``tf_echo_start``: from the process's start to its first printed answer, ``rostools tf
  echo odom cam`` beside the C++ ``tf_echo odom cam`` (tf1's tool on tf2) and tf2's python
  ``echo.py``, on one master with ``static_transform_publisher`` (base -> cam) and a rospy
  broadcaster of a moving frame (odom -> base, 64 Hz). Median of ``RUNS``, interleaved.
- ``tf_lookups``: lookups a second of ``TransformBuffer.lookup`` beside tf2's own
  ``BufferCore.lookup_transform_core`` (tf2_py, C++ behind Python) on the same data: a chain
  of ``DEPTH`` edges with 10 s of stamps at 100 Hz each, looked up between stamps (each edge
  interpolated), and at time 0 (the latest common time). Per second of CPU time, not of
  the wall: the machine's other work then counts for neither side.
"""

from __future__ import annotations

import json
import random
import statistics
import subprocess
import time

from benchmarks.common import (
    ROOT,
    SYSTEM_PYTHON,
    Result,
    master,
    ros_env,
    rostools_cmd,
    start,
    stop,
)

RUNS = 10
DEPTH = 4
STAMPS = 1000  # 10 s at 100 Hz
BROADCASTER = ROOT / "tests" / "support" / "ros1_nodes" / "tf_broadcaster.py"
TF_ECHO = "/usr/lib/tf/tf_echo"
ECHO_PY = "/usr/lib/tf2_tools/echo.py"


def _first_answer(argv: list[str], env: dict[str, str]) -> float:
    """Seconds from the start of ``argv`` to its first "Translation" line."""
    started = time.perf_counter()
    proc = start(argv, env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
    try:
        assert proc.stdout is not None
        for raw in proc.stdout:
            if b"Translation" in raw:
                return time.perf_counter() - started
        raise RuntimeError(f"{argv[0]} ended without an answer")
    finally:
        stop(proc)


def bench_tf_echo_start() -> Result:
    with master() as uri:
        env = ros_env(uri)
        pose = ["1", "2", "3", "0.1", "0.2", "0.3", "base", "cam"]
        static = start(
            ["/usr/lib/tf2_ros/static_transform_publisher", *pose],
            env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        moving = start(
            [SYSTEM_PYTHON, str(BROADCASTER), "odom", "base"],
            env,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        try:
            commands = {
                "ours": [*rostools_cmd(), "tf", "echo", "odom", "cam"],
                "tf_echo": [TF_ECHO, "odom", "cam"],
                "echo.py": [SYSTEM_PYTHON, ECHO_PY, "odom", "cam"],
            }
            _first_answer(commands["ours"], env)  # warm-up, and the graph is up
            samples: dict[str, list[float]] = {k: [] for k in commands}
            for _ in range(RUNS):
                for key, argv in commands.items():
                    samples[key].append(_first_answer(argv, env))
        finally:
            stop(moving)
            stop(static)
    med = {k: statistics.median(v) for k, v in samples.items()}
    return Result(
        "tf echo odom cam: start to its first answer (static + 64 Hz moving frame)",
        "ms",
        med["ours"] * 1e3,
        med["tf_echo"] * 1e3,
        "no slower than tf_echo (C++)",
        med["ours"] <= med["tf_echo"],
        f"median of {RUNS}, interleaved; tf2's echo.py {med['echo.py'] * 1e3:.0f} ms",
    )


def _case(seed: int = 1) -> dict[str, object]:
    """A chain w -> f1 -> ... -> fDEPTH, each edge STAMPS stamps 10 ms apart, and lookup times."""
    rng = random.Random(seed)
    sets = []
    for i in range(DEPTH):
        parent, child = ("w" if i == 0 else f"f{i}"), f"f{i + 1}"
        for k in range(STAMPS):
            q = [rng.gauss(0, 1) for _ in range(4)]
            n = sum(v * v for v in q) ** 0.5
            seven = [rng.uniform(-1, 1) for _ in range(3)] + [v / n for v in q]
            sets.append([parent, child, 1_000_000_000 + k * 10_000_000, seven])
    times = [1_000_000_000 + rng.randrange(0, (STAMPS - 1) * 10_000_000) for _ in range(1000)]
    return {"sets": sets, "times": times, "target": "w", "source": f"f{DEPTH}"}


_THEIRS = r"""
import json, sys, time
import rospy, tf2_py
from geometry_msgs.msg import TransformStamped
case = json.load(sys.stdin)
b = tf2_py.BufferCore(rospy.Duration(100))
for parent, child, stamp, seven in case["sets"]:
    m = TransformStamped()
    m.header.frame_id, m.child_frame_id = parent, child
    m.header.stamp = rospy.Time(stamp // 10**9, stamp % 10**9)
    t, q = m.transform.translation, m.transform.rotation
    t.x, t.y, t.z, q.x, q.y, q.z, q.w = seven
    b.set_transform(m, "bench")
target, source = case["target"], case["source"]
out = {}
for name, times in (("between", case["times"]), ("latest", [0] * len(case["times"]))):
    stamps = [rospy.Time(t // 10**9, t % 10**9) for t in times]
    done, start = 0, time.process_time()
    while time.process_time() - start < 2.0:
        for s in stamps:
            b.lookup_transform_core(target, source, s)
        done += len(stamps)
    out[name] = done / (time.process_time() - start)
print(json.dumps(out))
"""


def _ours(case: dict[str, object]) -> dict[str, float]:
    from rostools.tf.buffer import TransformBuffer
    from rostools.tf.records import Stamped

    b = TransformBuffer(100 * 1_000_000_000)
    for parent, child, stamp, seven in case["sets"]:  # type: ignore[attr-defined]
        b.set_transform(Stamped(parent, child, stamp, tuple(seven[:3]), tuple(seven[3:])))
    target, source = str(case["target"]), str(case["source"])
    times: list[int] = list(case["times"])  # type: ignore[call-overload]
    out = {}
    for name, ats in (("between", times), ("latest", [0] * len(times))):
        done, start = 0, time.process_time()
        while time.process_time() - start < 2.0:
            for t in ats:
                b.lookup(target, source, t)
            done += len(ats)
        out[name] = done / (time.process_time() - start)
    return out


def bench_tf_lookups() -> list[Result]:
    case = _case()
    theirs = json.loads(
        subprocess.run(
            [SYSTEM_PYTHON, "-c", _THEIRS],
            input=json.dumps(case),
            capture_output=True,
            text=True,
            check=True,
        ).stdout
    )
    ours = _ours(case)
    results = []
    for name, what in (("between", "between stamps"), ("latest", "at time 0 (latest)")):
        results.append(
            Result(
                f"tf lookups a second, {DEPTH} edges, {what}",
                "lookups/CPU s",
                ours[name],
                theirs[name],
                "at least half of tf2_py's BufferCore (C++)",
                ours[name] >= 0.5 * theirs[name],
                "TransformBuffer.lookup vs BufferCore.lookup_transform_core, same data, 2 CPU s",
            )
        )
    return results


BENCHMARKS = {"tf_echo_start": bench_tf_echo_start, "tf_lookups": bench_tf_lookups}
