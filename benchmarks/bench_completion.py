"""Tab completion round trip: `rostools topic echo /<TAB>` beside rosbash's `rostopic echo /<TAB>`.

Both completion functions run in one bash against the same master (the real rosmaster when it
is installed) holding 50 topics. Each is called ``RUNS`` times; the figure is the median wall
time of one call, measured inside bash with ``EPOCHREALTIME`` (bash's own start-up excluded,
each call's interpreter start-up included). ``completion_busy`` does the same beside two
processes spinning on the CPU at normal priority (a busy robot, on two cores), and reports the
fewest names a call offered (goal: every call offers all; the 300 ms deadline counts the
master's answer only, where it once counted the start-up as well).
"""

from __future__ import annotations

import statistics
import subprocess
import xmlrpc.client
from pathlib import Path

from benchmarks.bench_load_busy import busy
from benchmarks.common import ROOT, Result, master, ros_env, rostools_cmd

RUNS = 20
ROSBASH = Path("/usr/share/bash-completion/completions/rosbash")
TOPICS = 50

_TIMER = r"""
source {script}
for i in $(seq {runs}); do
    COMP_WORDS=({words}); COMP_CWORD={cword}; COMPREPLY=()
    t0=$EPOCHREALTIME; {function}; t1=$EPOCHREALTIME
    echo "${{#COMPREPLY[@]}} $t0 $t1"
done
"""


def _time_completion(
    script: Path, words: str, cword: int, function: str, env: dict[str, str]
) -> tuple[float, int]:
    """Median seconds of one completion call, and the fewest candidates a call offered."""
    code = _TIMER.format(script=script, runs=RUNS, words=words, cword=cword, function=function)
    out = subprocess.run(
        ["bash", "--norc", "-c", code], env=env, capture_output=True, text=True, check=True
    ).stdout
    rows = [line.split() for line in out.splitlines()]
    times = [float(t1) - float(t0) for _, t0, t1 in rows]
    return statistics.median(times), min(int(n) for n, _, _ in rows)


def _both(hogs: int) -> tuple[float, int, float | None, int | None]:
    """Ours and rosbash's: median seconds of a TAB and the fewest names offered."""
    exe_dir = Path(rostools_cmd()[0]).parent
    with master() as uri:
        proxy = xmlrpc.client.ServerProxy(uri)
        for i in range(TOPICS):
            proxy.registerPublisher(
                f"/pub{i}", f"/topic_{i}", "std_msgs/String", "http://127.0.0.1:9/"
            )
        env = ros_env(uri)
        env["PATH"] = f"{exe_dir}:{env['PATH']}"
        with busy(hogs):
            ours, offered = _time_completion(
                ROOT / "completions" / "rostools.bash", "rostools topic echo /", 3, "_rostools", env
            )
            theirs = their_offered = None
            if ROSBASH.exists():
                theirs, their_offered = _time_completion(
                    ROSBASH, "rostopic echo /", 2, "_roscomplete_rostopic", env
                )
    return ours, offered, theirs, their_offered


def bench_topic_completion() -> Result:
    ours, offered, theirs, their_offered = _both(0)
    assert their_offered in (None, offered), (their_offered, offered)
    return Result(
        f"completion of a topic name ({TOPICS} topics), one TAB",
        "ms",
        ours * 1e3,
        theirs * 1e3 if theirs is not None else None,
        "faster than rosbash",
        theirs is None or ours < theirs,
        f"median of {RUNS} calls of each shell function in one bash; both offered {offered} names",
    )


def bench_topic_completion_busy() -> Result:
    ours, offered, theirs, their_offered = _both(2)
    return Result(
        f"completion of a topic name ({TOPICS} topics), one TAB, beside two CPU hogs",
        "ms",
        ours * 1e3,
        theirs * 1e3 if theirs is not None else None,
        f"every TAB offers all {TOPICS} names, faster than rosbash",
        offered == TOPICS and (theirs is None or ours < theirs),
        f"median of {RUNS} calls; the fewest names a TAB offered: ours {offered}, "
        f"rosbash {their_offered if their_offered is not None else '-'}",
    )


BENCHMARKS = {"completion": bench_topic_completion, "completion_busy": bench_topic_completion_busy}
