"""Mutation testing of the modules where a silent bug costs most; prints a score per module.

Usage: python -m benchmarks.mutation [GROUP ...] [--jobs N] [--survivors] [--fresh]
       (groups: wire, master, bag, store, rates, snapshot, player; all by default)

mutmut plants one small bug at a time (a flipped comparison, a changed constant, a dropped
call) and runs the tests that reach the mutated function; a mutant that no test notices
"survives". Each group runs in its own scratch copy, ``mutants/GROUP`` (git ignores it), with
only the fast tests of its modules, so a mutant costs seconds, not a suite. mutmut keeps the
verdicts there: a second run tests only what changed; ``--survivors`` runs the last survivors
again (after adding tests); ``--fresh`` starts over. Not part of CI: a full run takes an hour
or more on two cores.

Survivors that cannot change behaviour are listed in ``benchmarks/mutation_equivalent.md``
with the reason, and left out of the score's denominator.
"""

from __future__ import annotations

import argparse
import ast
import contextlib
import json
import os
import shutil
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path

from benchmarks.common import ROOT

SCRATCH = ROOT / "mutants"
EQUIVALENT_FILE = ROOT / "benchmarks" / "mutation_equivalent.md"


@dataclass(frozen=True)
class Group:
    """Modules mutated together, and the tests that may kill their mutants."""

    modules: tuple[str, ...]
    tests: tuple[str, ...]
    #: Tests in those files that cannot run under mutmut, with the reason.
    deselect: tuple[tuple[str, str], ...] = ()


GROUPS: dict[str, Group] = {
    "wire": Group(
        modules=(
            "rostools/wire/codes.py",
            "rostools/wire/header.py",
            "rostools/wire/rosapi.py",
            "rostools/wire/tcpros.py",
            "rostools/wire/xmlrpc.py",
            "rostools/wire/xmlvalues.py",
        ),
        tests=(
            "tests/unit/test_wire_tcpros.py",
            "tests/unit/test_wire_xmlrpc.py",
            "tests/unit/test_xmlvalues.py",
            "tests/unit/test_coalesce.py",
            "tests/unit/test_wire_header.py",
            "tests/unit/test_wire_edges.py",
            "tests/unit/test_xmlvalues_edges.py",
            # rosapi's checks are reached through the Master API
            "tests/unit/test_master_api.py",
            "tests/unit/test_rosapi_checks.py",
        ),
        deselect=(
            (
                "tests/unit/test_wire_tcpros.py::test_frames_survive_any_chunking",
                "megabytes fed 3 bytes at a time: hours through mutmut's trampolines",
            ),
            (
                "tests/unit/test_xmlvalues.py::test_a_master_client_imports_no_xmlrpc_client",
                "counts the modules a child imports, and mutmut's trampolines import more",
            ),
        ),
    ),
    "master": Group(
        modules=("rostools/master/master_api.py", "rostools/master/registry.py"),
        tests=(
            "tests/unit/test_master_api.py",
            "tests/unit/test_master_params.py",
            "tests/unit/test_rosapi_checks.py",
        ),
    ),
    "bag": Group(
        modules=(
            "rostools/bag/formats/rosbag1_reader.py",
            "rostools/bag/formats/mcap_reader.py",
            "rostools/bag/tools/recover.py",
        ),
        tests=("tests/unit/bag",),
    ),
    "store": Group(
        modules=("rostools/msgs/store.py",),
        tests=(
            "tests/unit/test_store.py",
            "tests/unit/test_hostile_definitions.py",
            "tests/unit/test_codec.py",
            # the seven messages of an .action are built by the store
            "tests/unit/test_action_types.py",
        ),
    ),
    "rates": Group(modules=("rostools/rates.py",), tests=("tests/unit/test_rates.py",)),
    # bag snapshot's logic; its services and `bag trigger` are wire glue, tested end to end
    "snapshot": Group(
        modules=(
            "rostools/bag/live/ringbuffer.py",
            "rostools/bag/live/snapshot_live.py",
            "rostools/bag/live/snapshot_job.py",
            "rostools/bag/live/snapshot_srv.py",
            "rostools/bag/live/snapshot.py",
        ),
        tests=(
            "tests/unit/bag/test_ringbuffer.py",
            "tests/unit/bag/test_snapshot_live.py",
            "tests/unit/bag/test_snapshot_srv.py",
            "tests/unit/bag/test_snapshot_job.py",
            "tests/unit/bag/test_snapshotter.py",
            "tests/unit/test_snapshot_table.py",
        ),
    ),
    "player": Group(
        modules=("rostools/bag/live/player.py", "rostools/bag/live/play_control.py"),
        tests=("tests/unit/bag/test_play_control.py", "tests/unit/bag/test_player.py"),
    ),
}

#: mutmut's exit codes for a mutant (mutmut.stats.status_by_exit_code), as this report counts
#: them: a timeout or a crash is a mutant the tests noticed.
KILLED = {1, 3, 36, 24, -24, 152, 255, -11, -9, 37}
SURVIVED = {0}
NO_TESTS = {5, 33}
#: A mutant's CPU seconds: (its tests' time in the stats run + CONSTANT) * MULTIPLIER * 2.
TIMEOUT_MULTIPLIER = 4.0
TIMEOUT_CONSTANT = 2.0
#: Log lines say what happened; their text changes no behaviour, so it is not mutated.
DO_NOT_MUTATE = [r"^\s*(log|logger|_log|LOG)\.(debug|info|warning|error|exception)\("]


@dataclass
class Mutant:
    """One mutant's verdict, with where it is and what it changes."""

    name: str
    module: str
    status: str
    line: int = 0
    before: str = ""
    after: str = ""


@dataclass
class ModuleScore:
    """Killed / total for one module, equivalents left out."""

    module: str
    killed: int = 0
    total: int = 0
    equivalent: int = 0
    survivors: list[Mutant] = field(default_factory=list)

    @property
    def score(self) -> float:
        """Killed over the mutants that change behaviour."""
        counted = self.total - self.equivalent
        return self.killed / counted if counted else 1.0


def workspace(name: str, group: Group, fresh: bool) -> Path:
    """``mutants/NAME``: links to the sources and tests, and a pyproject with mutmut's table."""
    where = SCRATCH / name
    if fresh and where.exists():
        shutil.rmtree(where)
    where.mkdir(parents=True, exist_ok=True)
    for part in ("rostools", "tests"):
        link = where / part
        if not link.is_symlink():
            link.symlink_to(os.path.relpath(ROOT / part, where))
    selection: list[str] = list(group.tests)
    for test, _reason in group.deselect:
        selection += ["--deselect", test]
    table = {
        "source_paths": ["rostools"],
        "only_mutate": list(group.modules),
        "do_not_mutate_patterns": DO_NOT_MUTATE,
        # Our own options replace the suite's (-ra, --durations): one line per mutant is enough.
        "pytest_add_cli_args": ["-p", "no:cacheprovider", "-o", "addopts=", "--timeout=120"],
        "pytest_add_cli_args_test_selection": selection,
        "timeout_multiplier": TIMEOUT_MULTIPLIER,
        "timeout_constant": TIMEOUT_CONSTANT,
        "use_git_change_detection": False,
    }
    lines = [f"{key} = {json.dumps(value)}" for key, value in table.items()]
    base = (ROOT / "pyproject.toml").read_text()
    text = base + "\n[tool.mutmut]\n" + "\n".join(lines) + "\n"
    target = where / "pyproject.toml"
    if not target.exists() or target.read_text() != text:
        target.write_text(text)
    return where


def run_mutmut(where: Path, jobs: int, names: list[str]) -> int:
    """``mutmut run`` in the group's scratch copy; its chatter goes to ``mutmut.log`` there."""
    env = dict(os.environ)
    env.setdefault("ROSTOOLS_CORPUS", str(ROOT.parent / "shared" / "corpus"))
    env.pop("CI", None)  # a skip under mutmut is not a failure of the suite
    log = where / "mutmut.log"
    argv = [sys.executable, "-m", "mutmut", "run", "--max-children", str(jobs), *names]
    with log.open("w") as out:
        done = subprocess.run(
            argv, cwd=where, env=env, stdout=out, stderr=subprocess.STDOUT, check=False
        )
    return done.returncode


def _code_status(code: int | None) -> str:
    if code in KILLED:
        return "killed"
    if code in SURVIVED:
        return "survived"
    if code in NO_TESTS:
        return "no tests"
    if code is None:
        return "not checked"
    return f"suspicious ({code})"


def verdicts(where: Path, group: Group) -> list[Mutant]:
    """Every mutant of the group with its verdict, from mutmut's ``.meta`` files.

    mutmut forgets the verdicts of the mutants it does not run again when the tests change
    (``--survivors`` after adding tests). A kill is kept in ``verdicts.json`` beside them, for
    as long as the mutated function is unchanged: tests are only ever added, so a mutant
    that was killed stays killed.
    """
    saved_path = where / "verdicts.json"
    saved: dict[str, list[object]] = (
        json.loads(saved_path.read_text()) if saved_path.exists() else {}
    )
    found: list[Mutant] = []
    for module in group.modules:
        meta_path = where / "mutants" / (module + ".meta")
        if not meta_path.exists():
            continue
        meta = json.loads(meta_path.read_text())
        hashes = meta.get("hash_by_function_name", {})
        for name, code in sorted(meta["exit_code_by_key"].items()):
            function = name.rsplit(".", 1)[-1].split("__mutmut_")[0]
            digest = hashes.get(function)
            before = saved.get(name)
            if code is None and before is not None and before[1] == digest:
                code = before[0]
            if code is not None:
                saved[name] = [code, digest]
            found.append(Mutant(name=name, module=module, status=_code_status(code)))
    saved_path.write_text(json.dumps(saved))
    return found


@contextlib.contextmanager
def cwd(path: Path) -> Iterator[None]:
    """Run in ``path`` (mutmut's helpers read ``mutants/`` from the working directory)."""
    before = Path.cwd()
    os.chdir(path)
    try:
        yield
    finally:
        os.chdir(before)


def function_span(source: str, mangled: str) -> tuple[int, int]:
    """First and last line of the function mutmut calls ``mangled`` (x_f, xǁClassǁmethod)."""
    body = ast.parse(source).body
    if "ǁ" in mangled:
        _, cls, wanted = mangled.split("ǁ")
        for node in body:
            if isinstance(node, ast.ClassDef) and node.name == cls:
                body = node.body
                break
    else:
        wanted = mangled.removeprefix("x_")
    for item in body:
        if isinstance(item, ast.FunctionDef | ast.AsyncFunctionDef) and item.name == wanted:
            return item.lineno, item.end_lineno or item.lineno
    return 1, source.count("\n") + 1


def locate(where: Path, mutant: Mutant) -> None:
    """Fill in the line of the original file and the text before and after the mutation."""
    from mutmut.mutation.diff_apply import get_diff_for_mutant

    with cwd(where):
        diff = get_diff_for_mutant(mutant.name, path=mutant.module)
    removed = [
        line[1:]
        for line in diff.splitlines()
        if line.startswith("-") and not line.startswith("---")
    ]
    added = [
        line[1:]
        for line in diff.splitlines()
        if line.startswith("+") and not line.startswith("+++")
    ]
    mutant.before = " / ".join(s.strip() for s in removed)
    mutant.after = " / ".join(s.strip() for s in added)
    source = (ROOT / mutant.module).read_text()
    start, end = function_span(source, mutant.name.rsplit(".", 1)[-1].split("__mutmut_")[0])
    lines = source.splitlines()
    probe = removed[0].strip() if removed else ""
    mutant.line = start
    for number in range(start, end + 1):
        if probe and lines[number - 1].strip() == probe:
            mutant.line = number
            break


def equivalents() -> dict[tuple[str, str, str], str]:
    """``mutation_equivalent.md`` as (module, before, after) -> why no behaviour changes."""
    table: dict[tuple[str, str, str], str] = {}
    if not EQUIVALENT_FILE.exists():
        return table
    for line in EQUIVALENT_FILE.read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split(" | ")]
        if len(cells) != 4 or not cells[0].startswith("`rostools/"):
            continue
        module, before, after, reason = (c.strip("`") if i < 3 else c for i, c in enumerate(cells))
        table[(module, before.replace("\\|", "|"), after.replace("\\|", "|"))] = reason
    return table


def score(group_mutants: list[Mutant], where: Path) -> list[ModuleScore]:
    """Scores per module; survivors located and checked against the table of equivalents."""
    known = equivalents()
    by_module: dict[str, ModuleScore] = {}
    for m in group_mutants:
        s = by_module.setdefault(m.module, ModuleScore(m.module))
        s.total += 1
        if m.status == "killed":
            s.killed += 1
            continue
        if m.status == "not checked":
            continue
        locate(where, m)
        if (m.module, m.before, m.after) in known:
            s.equivalent += 1
        else:
            s.survivors.append(m)
    return list(by_module.values())


def report(scores: list[ModuleScore]) -> None:
    """One line per module, then each survivor as file:line, what changed."""
    for s in scores:
        print(
            f"{s.module}: {s.killed}/{s.total - s.equivalent} killed ({100 * s.score:.1f}%)"
            f"{f', {s.equivalent} equivalent' if s.equivalent else ''}"
        )
        for m in s.survivors:
            print(f"  {m.module}:{m.line}: {m.status}: `{m.before}` -> `{m.after}`  [{m.name}]")


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("groups", nargs="*", metavar="GROUP", help=", ".join(GROUPS))
    parser.add_argument("--jobs", type=int, default=2, help="mutants at a time (default 2)")
    parser.add_argument(
        "--survivors",
        action="store_true",
        help="test the last run's survivors again, e.g. after adding tests",
    )
    parser.add_argument("--fresh", action="store_true", help="forget earlier verdicts")
    parser.add_argument("--report", action="store_true", help="only report the last verdicts")
    parser.add_argument("--match", default="", help="with --survivors: only mutants named so")
    args = parser.parse_args()
    chosen = args.groups or list(GROUPS)
    unknown = [g for g in chosen if g not in GROUPS]
    if unknown:
        parser.error(f"unknown group {unknown[0]!r} (groups: {', '.join(GROUPS)})")
    summary: dict[str, object] = {"when": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "modules": []}
    all_scores: list[ModuleScore] = []
    for name in chosen:
        group = GROUPS[name]
        where = workspace(name, group, args.fresh)
        if not args.report:
            names: list[str] = []
            if args.survivors:
                names = [
                    m.name
                    for m in verdicts(where, group)
                    if m.status != "killed" and args.match in m.name
                ]
                if not names:
                    continue
            started = time.monotonic()
            print(
                f"mutating {name} ({len(group.modules)} modules; log: "
                f"{(where / 'mutmut.log').relative_to(ROOT)}) ...",
                file=sys.stderr,
                flush=True,
            )
            code = run_mutmut(where, args.jobs, names)
            print(
                f"  {name}: mutmut exit {code} after {time.monotonic() - started:.0f} s",
                file=sys.stderr,
            )
        all_scores += score(verdicts(where, group), where)
    report(all_scores)
    summary["modules"] = [
        {
            "module": s.module,
            "killed": s.killed,
            "total": s.total,
            "equivalent": s.equivalent,
            "score": round(s.score, 4),
            "survivors": [
                {
                    "where": f"{m.module}:{m.line}",
                    "status": m.status,
                    "before": m.before,
                    "after": m.after,
                    "mutant": m.name,
                }
                for m in s.survivors
            ],
        }
        for s in all_scores
    ]
    out = ROOT / "benchmarks" / "results" / f"mutation-{time.strftime('%Y%m%d-%H%M%S')}.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(summary, indent=2, ensure_ascii=False) + "\n")
    print(f"\nwrote {out.relative_to(ROOT)}", file=sys.stderr)
    below = [s.module for s in all_scores if s.score < 0.9]
    return 1 if below else 0


if __name__ == "__main__":
    sys.exit(main())
