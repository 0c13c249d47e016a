"""The fuzz suites (tests/fuzz) for hours: round after round, each with a new seed.

Usage: python -m benchmarks.fuzz [--hours H] [--examples N] [--seed S] [--tests PATH]

CI runs every fuzz test with 150 cases and one fixed seed. This runs the same tests with
``--examples`` cases each, seed ``S``, ``S + 1``, ... until ``--hours`` have passed, and
writes a summary (cases, failures, the slowest round, peak memory) to
``benchmarks/results/fuzz-STAMP.json``. A failing round keeps its pytest output beside it;
rerun it with ``ROSTOOLS_FUZZ_SEED`` and ``ROSTOOLS_FUZZ_EXAMPLES`` set as the summary says.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time
from pathlib import Path

from benchmarks.common import ROOT

#: pytest's per-test limit for one round: generous, since a test runs ``examples`` cases;
#: it is what turns a hang into a failure.
SECONDS_PER_CASE = 1.0


def _round(seed: int, examples: int, out: Path, tests: str) -> dict[str, object]:
    """One pass over the fuzz tests (``tests``: tests/fuzz or one of its files); its outcome."""
    env = dict(os.environ, ROSTOOLS_FUZZ_SEED=str(seed), ROSTOOLS_FUZZ_EXAMPLES=str(examples))
    limit = max(120, int(examples * SECONDS_PER_CASE))
    began = time.monotonic()
    done = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", f"--timeout={limit}",
         tests],
        cwd=ROOT, env=env, capture_output=True, text=True, check=False,
    )  # fmt: skip
    tail = done.stdout.strip().splitlines()[-1:] or [""]
    result: dict[str, object] = {
        "seed": seed,
        "examples": examples,
        "seconds": round(time.monotonic() - began, 1),
        "exit": done.returncode,
        "summary": tail[0],
    }
    if done.returncode != 0:
        log = out.with_name(f"{out.stem}-seed{seed}.log")
        log.write_text(done.stdout + done.stderr)
        result["log"] = log.name
    return result


def _tests(tests: str) -> int:
    """How many fuzz tests there are (cases per round = tests x examples)."""
    found = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "--collect-only", "-p", "no:cacheprovider",
         tests],
        cwd=ROOT, capture_output=True, text=True, check=False,
    )  # fmt: skip
    return sum(1 for line in found.stdout.splitlines() if "::" in line)


def main() -> int:
    """Run rounds until the time is up; print and write the summary."""
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--hours", type=float, default=1.0)
    parser.add_argument("--examples", type=int, default=1000)
    parser.add_argument("--seed", type=int, default=int(time.time()) % 1_000_000)
    parser.add_argument("--tests", default="tests/fuzz", help="One suite, e.g. its file.")
    args = parser.parse_args()
    out = ROOT / "benchmarks" / "results" / f"fuzz-{time.strftime('%Y%m%d-%H%M%S')}.json"
    tests = _tests(args.tests)
    rounds: list[dict[str, object]] = []
    end = time.monotonic() + args.hours * 3600
    seed = args.seed
    while not rounds or time.monotonic() < end:
        rounds.append(_round(seed, args.examples, out, args.tests))
        print(json.dumps(rounds[-1]), flush=True)
        seed += 1
    summary = {
        "tests": args.tests,
        "rounds": len(rounds),
        "cases": len(rounds) * tests * args.examples,
        "failed_rounds": sum(1 for r in rounds if r["exit"] != 0),
        "slowest_round_s": max(float(str(r["seconds"])) for r in rounds),
        # ru_maxrss of the children: the largest pytest process, so the largest case too.
        "peak_rss_mb": round(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024, 1),
        "round_log": rounds,
    }
    out.write_text(json.dumps(summary, indent=2) + "\n")
    print(f"{summary['cases']:,} cases in {len(rounds)} rounds, "
          f"{summary['failed_rounds']} failed, peak {summary['peak_rss_mb']} MB; wrote "
          f"{out.relative_to(ROOT)}")  # fmt: skip
    return 1 if summary["failed_rounds"] else 0


if __name__ == "__main__":
    sys.exit(main())
