"""Shared pieces of the benchmarks: results, timing whole processes, the install under test."""

from __future__ import annotations

import json
import os
import shutil
import statistics
import subprocess
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BENCH_VENV = ROOT / "benchmarks" / ".venv"
SYSTEM_PYTHON = "/usr/bin/python3"


@dataclass
class Result:
    """One measurement of rostools beside the real ROS 1 tool, from the same run."""

    name: str
    unit: str
    ours: float
    theirs: float | None
    target: str
    met: bool | None
    note: str = ""

    @property
    def ratio(self) -> float | None:
        """ours / theirs."""
        if self.theirs in (None, 0):
            return None
        return self.ours / self.theirs  # type: ignore[operator]

    def as_dict(self) -> dict[str, object]:
        """For the JSON report."""
        d = asdict(self)
        d["ratio"] = self.ratio
        return d


def rostools_cmd() -> list[str]:
    """The rostools console script of a normal (non-editable) install, as users get it.

    An editable install adds a meta-path finder that costs ~15 ms at every start-up.
    """
    exe = BENCH_VENV / "bin" / "rostools"
    stamp = BENCH_VENV / ".installed-from"
    source_mtime = str(max(p.stat().st_mtime for p in (ROOT / "rostools").rglob("*.py")))
    if not exe.exists() or not stamp.exists() or stamp.read_text() != source_mtime:
        if not (BENCH_VENV / "bin" / "python").exists():
            subprocess.run([sys.executable, "-m", "venv", str(BENCH_VENV)], check=True)
        subprocess.run(
            [
                str(BENCH_VENV / "bin" / "pip"),
                "install",
                "-q",
                "--force-reinstall",
                "--no-deps",
                str(ROOT),
            ],
            check=True,
        )
        subprocess.run([str(BENCH_VENV / "bin" / "pip"), "install", "-q", str(ROOT)], check=True)
        stamp.write_text(source_mtime)
    return [str(exe)]


def have(tool: str) -> bool:
    """Whether a real ROS 1 tool is on PATH."""
    return shutil.which(tool) is not None


def time_commands(
    commands: dict[str, Sequence[str]],
    runs: int = 30,
    warmup: int = 3,
    env: dict[str, str] | None = None,
) -> dict[str, float]:
    """Median wall time in seconds of each command, runs interleaved so drift hits all alike."""
    samples: dict[str, list[float]] = {k: [] for k in commands}
    for i in range(warmup + runs):
        for key, argv in commands.items():
            start = time.perf_counter()
            proc = subprocess.run(
                argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env, check=False
            )
            elapsed = time.perf_counter() - start
            if proc.returncode != 0:
                raise RuntimeError(f"{' '.join(argv)} failed: {proc.stderr.decode()[-500:]}")
            if i >= warmup:
                samples[key].append(elapsed)
    return {k: statistics.median(v) for k, v in samples.items()}


def throughput(fn: Callable[[], int], seconds: float = 2.0) -> float:
    """Items per second of ``fn`` (which returns how many items it did), over ``seconds``."""
    done = 0
    start = time.perf_counter()
    while (elapsed := time.perf_counter() - start) < seconds:
        done += fn()
    return done / elapsed


def write_report(results: list[Result], path: Path) -> None:
    """The JSON report."""
    path.parent.mkdir(parents=True, exist_ok=True)
    payload = {
        "when": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "machine": {"cpus": os.cpu_count(), "python": sys.version.split()[0]},
        "results": [r.as_dict() for r in results],
    }
    path.write_text(json.dumps(payload, indent=2) + "\n")
