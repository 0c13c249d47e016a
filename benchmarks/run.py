"""Run the benchmarks side by side with the real ROS 1 tools; print ratios, write JSON.

Usage: python -m benchmarks.run [NAME ...]   (names: see --list)
"""

from __future__ import annotations

import argparse
import importlib
import sys
import time

from benchmarks.common import ROOT, Result, merge_latest, write_report

MODULES = [
    "benchmarks.bench_msg",
    "benchmarks.bench_startup",
    "benchmarks.bench_master",
    "benchmarks.bench_hostile",
    "benchmarks.bench_topic",
    "benchmarks.bench_topic_cpp",
    "benchmarks.bench_service",
    "benchmarks.bench_bag",
    "benchmarks.bench_bag_live",
    "benchmarks.bench_libraries",
    "benchmarks.bench_workbench",
    "benchmarks.bench_plot",
    "benchmarks.bench_completion",
    "benchmarks.bench_network",
    "benchmarks.bench_load",
    "benchmarks.bench_load_memory",
    "benchmarks.bench_load_busy",
    "benchmarks.bench_snapshot",
    "benchmarks.bench_fixture",
    "benchmarks.bench_demo",
    "benchmarks.bench_bridge",
    "benchmarks.bench_rosbridge",
    "benchmarks.bench_log",
    "benchmarks.bench_tf",
    "benchmarks.bench_ros2",
    "benchmarks.bench_tables",
]


def collect() -> dict[str, object]:
    found: dict[str, object] = {}
    for name in MODULES:
        found.update(importlib.import_module(name).BENCHMARKS)
    return found


def fmt(value: float | None) -> str:
    if value is None:
        return "-"
    return f"{value:,.1f}" if value >= 100 else f"{value:.3g}"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("names", nargs="*")
    parser.add_argument("--list", action="store_true")
    args = parser.parse_args()
    benches = collect()
    if args.list:
        print("\n".join(benches))
        return 0
    chosen = args.names or list(benches)
    results: list[Result] = []
    for name in chosen:
        print(f"running {name} ...", file=sys.stderr, flush=True)
        out = benches[name]()  # type: ignore[operator]
        results.extend(out if isinstance(out, list) else [out])
    rows = [("benchmark", "unit", "rostools", "ROS 1", "ratio", "target", "met")]
    for r in results:
        met = "-" if r.met is None else ("yes" if r.met else "NO")
        rows.append((r.name, r.unit, fmt(r.ours), fmt(r.theirs), fmt(r.ratio), r.target, met))
    widths = [max(len(row[i]) for row in rows) for i in range(len(rows[0]))]
    for row in rows:
        print("  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True)))
    stamp = time.strftime("%Y%m%d-%H%M%S")
    report = ROOT / "benchmarks" / "results" / f"{stamp}.json"
    write_report(results, report)
    merge_latest(results, ROOT / "benchmarks" / "results" / "latest.json")
    print(f"\nwrote {report.relative_to(ROOT)}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
