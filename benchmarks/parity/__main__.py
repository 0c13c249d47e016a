"""Run every parity case; print the counts per class and tool; write the JSON report.

Usage: python -m benchmarks.parity [--only REGEX] [--masters roscore,rostools] [--keep]

Builds the graph on a real roscore, records its bags with real rosbag, runs every online
case there (ROS 1 tool, then rostools), then builds the same graph on ``rostools core``
and runs them again; the offline cases (types, bags) run once. Writes
``benchmarks/results/parity-STAMP.json``: every case with its class, and for each defect
a short diff. Exit 1 when a case is a defect.
"""

from __future__ import annotations

import argparse
import json
import re
import shutil
import sys
import tempfile
import time
from collections import Counter
from collections.abc import Sequence
from pathlib import Path

from benchmarks.parity import documented
from benchmarks.parity.cases import online_cases
from benchmarks.parity.cases_offline import offline_cases
from benchmarks.parity.compare import Judgement, Output, Verdict, judge, worst
from benchmarks.parity.graph import graph, have_ros1, record_bags, rostools_argv
from benchmarks.parity.runner import Case, Place, run_side
from tests.support.env import CORPUS, ROOT
from tests.support.procs import free_port, ros_env

DATA_FILES = {
    "text.txt": "some text\nsecond line\n",
    "params.yaml": "a: 1\nb: {c: [1, 2], d: 'x'}\nangle: deg(90)\ns: |\n  two\n  lines\n",
    "multi.yaml": "_ns: scratch\nfirst: 1\n---\n_ns: scratch/more\nsecond: [a, b]\n",
    "bad.yaml": "a: [1, 2\nb: {\n",
    "msgs.yaml": "data: one\n---\ndata: two\n",
}

Run = dict[str, object]


def _trim(out: Output, limit: int = 1500) -> dict[str, object]:
    def cut(text: str) -> str:
        return text if len(text) <= limit else text[:limit] + f"... ({len(text)} chars)"

    return {"exit": out.code, "stdout": cut(out.stdout), "stderr": cut(out.stderr),
            "effects": cut(out.effects), "stopped": out.stopped}  # fmt: skip


def _pair(case: Case, place: Place, master: str) -> Run:
    ros1 = run_side(case, place, "ros1")
    ours = run_side(case, place, "ours")
    verdict: Judgement = judge(ros1, ours, case.pairing, live=case.live)
    row: Run = {"master": master, "class": verdict.verdict.value, "documented": list(verdict.rules)}
    if verdict.verdict in (Verdict.DEFECT, Verdict.ROS1_FAILURE):
        row["diff"] = verdict.detail
        row["ros1"], row["rostools"] = _trim(ros1), _trim(ours)
    return row


def _prepare_data(data: Path) -> None:
    data.mkdir(parents=True, exist_ok=True)
    for name, text in DATA_FILES.items():
        (data / name).write_text(text)


def _run_cases(
    cases: Sequence[Case], place: Place, master: str, runs: dict[str, list[Run]]
) -> None:
    for n, case in enumerate(cases, 1):
        began = time.monotonic()
        row = _pair(case, place, master)
        runs.setdefault(case.id, []).append(row)
        print(f"[{master} {n}/{len(cases)}] {case.id}: {row['class']} "
              f"({time.monotonic() - began:.1f} s)", file=sys.stderr, flush=True)  # fmt: skip


def table(cases: Sequence[Case], runs: dict[str, list[Run]]) -> str:
    """Counts per class, per tool: of cases (their worst run) and of paired runs."""
    classes = [v.value for v in Verdict]
    tools = sorted({c.tool for c in cases})
    per_case = {c.id: _class(runs, c) for c in cases}
    lines = [f"{'tool':<11}{'cases':>6}{'runs':>6}" + "".join(f"{k:>14}" for k in classes)]
    for tool in [*tools, "all"]:
        chosen = [c for c in cases if tool in ("all", c.tool) and c.id in runs]
        counts = Counter(per_case[c.id].value for c in chosen)
        n_runs = sum(len(runs[c.id]) for c in chosen)
        lines.append(
            f"{tool:<11}{len(chosen):>6}{n_runs:>6}" + "".join(f"{counts[k]:>14}" for k in classes)
        )
    by_run = Counter(str(r["class"]) for c in cases for r in runs.get(c.id, []))
    lines.append(f"{'paired runs':<23}" + "".join(f"{by_run[k]:>14}" for k in classes))
    lines.append("(class counts are of cases, each as its worst paired run, then of paired runs)")
    return "\n".join(lines)


def main() -> int:
    """Run the cases, print the table and the defects, write the report."""
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("--only", default="", help="run the cases whose id matches this regex")
    parser.add_argument("--masters", default="roscore,rostools")
    parser.add_argument("--keep", action="store_true", help="keep the scratch folder")
    args = parser.parse_args()
    missing = have_ros1()
    if missing is not None:
        print(f"parity: {missing}", file=sys.stderr)
        return 2
    unsupported = documented.check_docs(ROOT)
    if unsupported:
        print(f"parity: the docs no longer say what these differences cite: {unsupported}",
              file=sys.stderr)  # fmt: skip
        return 2
    pick = re.compile(args.only)
    online = [c for c in online_cases() if pick.search(c.id)]
    offline = [c for c in offline_cases(CORPUS) if pick.search(c.id)]
    scratch = Path(tempfile.mkdtemp(prefix="rostools-parity-"))
    data = scratch / "data"
    _prepare_data(data)
    rostools = tuple(rostools_argv())
    runs: dict[str, list[Run]] = {}
    began = time.monotonic()
    try:
        masters = args.masters.split(",")
        for n, kind in enumerate(masters):
            with graph(kind, scratch / kind) as g:
                if n == 0:
                    record_bags(g, data)
                    shutil.copy2(data / "graph.bag", data / "graph.orig.bag")
                place = Place(g, g.env, data, scratch, CORPUS, rostools)
                _run_cases(online, place, kind, runs)
        env = ros_env(f"http://127.0.0.1:{free_port()}/", scratch / "offline")
        _run_cases(offline, Place(None, env, data, scratch, CORPUS, rostools), "none", runs)
    finally:
        if not args.keep:
            shutil.rmtree(scratch, ignore_errors=True)
    cases = [*online, *offline]
    print(table(cases, runs))
    report = _report(cases, runs, time.monotonic() - began)
    out = ROOT / "benchmarks" / "results" / f"parity-{time.strftime('%Y%m%d-%H%M%S')}.json"
    out.write_text(json.dumps(report, indent=2) + "\n")
    defects = [c for c in cases if _class(runs, c) is Verdict.DEFECT]
    for c in defects:
        print(f"\nDEFECT {c.id}: {c.ros1}  |  rostools {c.ours}")
        first = next(r for r in runs[c.id] if r["class"] == Verdict.DEFECT.value)
        print(f"  on {first['master']}:\n    " + str(first["diff"]).replace("\n", "\n    "))
    print(f"\nwrote {out.relative_to(ROOT)}", file=sys.stderr)
    return 1 if defects else 0


def _class(runs: dict[str, list[Run]], c: Case) -> Verdict:
    """A case's class: its worst paired run."""
    return worst([Verdict(str(r["class"])) for r in runs.get(c.id, [])])


def _report(cases: Sequence[Case], runs: dict[str, list[Run]], seconds: float) -> dict[str, object]:
    items = []
    for c in cases:
        rows = runs.get(c.id, [])
        items.append({
            "id": c.id, "tool": c.tool, "ros1": c.ros1, "rostools": f"rostools {c.ours}",
            "class": _class(runs, c).value, "runs": rows,
        })  # fmt: skip
    counts = Counter(str(i["class"]) for i in items)
    by_run = Counter(str(r["class"]) for rows in runs.values() for r in rows)
    return {
        "when": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "seconds": round(seconds),
        "cases": items,
        "summary": {"cases": len(items), "paired_runs": sum(len(r) for r in runs.values()),
                    **{v.value: counts[v.value] for v in Verdict},
                    "runs": {v.value: by_run[v.value] for v in Verdict}},
        "documented_differences": [
            {"key": x.key, "reason": x.reason, "readme": x.readme} for x in documented.ALL
        ],
    }  # fmt: skip


if __name__ == "__main__":
    sys.exit(main())
