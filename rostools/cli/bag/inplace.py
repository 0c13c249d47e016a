"""Rewriting bags in place, rosbag's way, for ``compress``, ``decompress`` and ``reindex``.

Each bag is written beside itself and swapped in, its original kept as ``NAME.orig.bag``
(or written into ``--output-dir``). As rosbag does, a bad file does not stop the run: it is
skipped with a line saying why, and the others are done. The exit code is the worst of them.
"""

from __future__ import annotations

import dataclasses
import sys
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rostools.bag.formats.model import counted, lost_data
from rostools.cli.bag.shared import copy_command
from rostools.errors import RostoolsError, UsageError, one_line

if TYPE_CHECKING:
    from rostools.bag.tools.ops import CopyReport
    from rostools.cli.output import Format

#: Does one bag: ``(source, where to write, the bag it replaces or None)`` -> what was lost.
Step = Callable[[Path, Path, Path | None], list[str]]


def backup_name(path: Path) -> Path:
    """Where the original of ``path`` is kept: ``x.bag`` -> ``x.orig.bag``."""
    return path.with_name(path.stem + ".orig" + path.suffix)


def swap(path: Path, written: Path, keep: Path | None) -> None:
    """Move the original to ``x.orig.bag`` and the new file into its place."""
    if keep is not None:
        path.replace(backup_name(path))
        written.replace(path)


def each_in_place(
    bags: list[Path], output_dir: Path | None, force: bool, quiet: bool, label: str, step: Step
) -> None:
    """Run ``step`` on each bag; skip, with a line, those that cannot be done.

    A bag whose backup exists (without ``--force``) is skipped with rosbag's own line and
    counts as done (exit 0, as rosbag; ``-q`` leaves the line out, as rosbag's). Any other
    failure is a ``Skipping NAME: why`` line; at the end, one error line with the highest exit
    code of the failures (6 when data was lost). A single bag that fails is its own error.
    """
    if output_dir is not None and not output_dir.is_dir():
        raise UsageError(f"--output-dir {output_dir} is not a folder")
    failed: list[tuple[Path, RostoolsError]] = []
    skipped: list[Path] = []
    lost: list[str] = []
    for path in bags:
        dst, keep = (output_dir / path.name, None) if output_dir is not None else (path, path)
        if keep is None and dst.resolve() == path.resolve():
            keep = path  # --output-dir is the bag's own folder: in place, as rosbag
        if keep is not None:
            backup = backup_name(path)
            if backup.exists() and not force:
                if not quiet:
                    sys.stderr.write(f"Skipping {path}. Backup path {backup} already exists.\n")
                skipped.append(path)
                continue
            dst = path.with_name(path.name + ".tmp")
        try:
            lost += step(path, dst, keep)
        except RostoolsError as err:
            if len(bags) == 1:
                raise
            sys.stderr.write(one_line(f"Skipping {path}: {err}") + "\n")
            failed.append((path, err))
            skipped.append(path)
    if failed or lost:
        raise _outcome(label, len(bags), output_dir, skipped, failed, lost)


def _outcome(
    label: str,
    count: int,
    output_dir: Path | None,
    skipped: list[Path],
    failed: list[tuple[Path, RostoolsError]],
    lost: list[str],
) -> RostoolsError:
    """One error for the whole run, with the worst exit code among its files."""
    kept = "" if output_dir else " (each original is kept as NAME.orig.bag)"
    done = f"{count - len(skipped)} of " if skipped else ""
    what = f"{label}ed {done}{counted(count, 'bag')}{kept}"
    if skipped:
        what += "; skipped " + ", ".join(str(p) for p in skipped)
    err: RostoolsError = lost_data(what, lost) if lost else RostoolsError(what)
    err.exit_code = max([e.exit_code for _, e in failed] + [err.exit_code if lost else 0])
    return err


def copy_in_place(
    bags: list[Path],
    output_dir: Path | None,
    force: bool,
    fmt: Format,
    quiet: bool,
    label: str,
    run: Callable[[Path, Path, Any], CopyReport],
) -> None:
    """rosbag compress's way: write beside, keep the original as ``x.orig.bag``.

    ``run(source, destination, progress)`` copies one bag. A damaged bag is rewritten with
    what reads (the original is kept all the same); exit 6 at the end, naming what was left
    out.
    """

    def one(path: Path, dst: Path, keep: Path | None) -> list[str]:
        def step(progress: Any) -> CopyReport:
            return dataclasses.replace(run(path, dst, progress), output=keep or dst)

        report = copy_command(fmt, quiet, label, step, check=False, say=not quiet)
        swap(path, dst, keep)
        return list(report.lost)

    each_in_place(bags, output_dir, force, quiet, label, one)
