"""``bag export`` as a whole: plan the tables, then export the bags in parallel processes.

The plan reads each bag's index (``bag_info``): which topics and definitions it holds. A
topic with more than one md5sum among the bags gets one table per definition (``layout``).
Then one ``BagTask`` per bag runs ``dataset.export_bag`` in a pool of ``jobs`` processes
(spawned: the same in every process whatever the parent holds, as under Dask), with the rows
each writes counted back through a queue for the progress bar.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

from rostools.bag.tables import dataset
from rostools.bag.tables.dataset import BagExport, BagTask, TableChoice, export_bag
from rostools.bag.tables.layout import bag_key, table_key
from rostools.errors import NotFoundError, RostoolsError, UsageError

#: Seconds between looks at the pool for the progress bar; not a deadline.
POLL_PERIOD: Final = 0.2


@dataclass(frozen=True)
class Split:
    """A topic whose definition changes between the bags: one table per md5sum."""

    topic: str
    tables: tuple[tuple[str, str], ...]  # (md5sum, key)


@dataclass(frozen=True)
class Plan:
    """The tasks of an export, the rows the bags hold (for progress), and the splits."""

    tasks: tuple[BagTask, ...]
    format: str
    messages: int
    splits: tuple[Split, ...]
    types: dict[str, str]  # topic -> type


@dataclass(frozen=True)
class ExportReport:
    """What ``bag export`` wrote, bag by bag, and what it could not read."""

    out: Path
    plan: Plan
    bags: tuple[BagExport, ...]

    @property
    def lost(self) -> list[str]:
        """What damage left out, for every bag."""
        return [line for bag in self.bags for line in bag.lost]

    @property
    def skipped(self) -> dict[str, int]:
        """Each table that could not be read: its line (said once) and its exit code."""
        return {line: code for bag in self.bags for line, code in bag.skipped}


def plan_export(
    paths: Sequence[Path],
    out: Path,
    *,
    topics: Sequence[str] | None = None,
    fmt: str = "parquet",
    start_ns: int | None = None,
    end_ns: int | None = None,
    flatten: bool = False,
    batch_rows: int = dataset.BATCH_ROWS,
) -> Plan:
    """One task per bag; missing bags, clashing names and unknown topics refused first."""
    from rostools.bag.formats.access import open_bag, require_ros1

    seen: dict[str, Path] = {}
    for path in paths:
        if not path.is_file():
            raise NotFoundError(f"no such bag: {path}")
        key = bag_key(path)
        if key in seen:
            raise UsageError(
                f"two bags would share bag={key}: {seen[key]} and {path}",
                hint="rename one: a bag's directory is its name without the suffix",
            )
        seen[key] = path
    held: list[dict[tuple[str, str], int]] = []
    starts: list[int | None] = []
    types: dict[str, str] = {}
    for path in paths:
        with open_bag(path) as reader:  # ROS 2 refused now, before OUT is made
            require_ros1(reader, "bag export", topics)
            info = reader.info()
        starts.append(info.start_ns)
        counts: dict[tuple[str, str], int] = {}
        for conn in info.connections:
            if topics and conn.topic not in topics:
                continue
            types.setdefault(conn.topic, conn.type)
            pair = (conn.topic, conn.md5sum)
            counts[pair] = counts.get(pair, 0) + info.connection_counts.get(conn.id, 0)
        held.append(counts)
    missing = [t for t in topics or () if t not in types]
    if missing:
        raise NotFoundError(f"no bag holds {', '.join(missing)}")
    md5s: dict[str, set[str]] = {}
    for counts in held:
        for topic, md5 in counts:
            md5s.setdefault(topic, set()).add(md5)
    splits = tuple(
        Split(t, tuple((m, table_key(t, m)) for m in sorted(ms)))
        for t, ms in sorted(md5s.items()) if len(ms) > 1
    )  # fmt: skip
    split_topics = {s.topic for s in splits}
    tasks = tuple(
        BagTask(
            str(path), str(out),
            tuple(TableChoice(t, m, table_key(t, m if t in split_topics else None))
                  for t, m in sorted(counts)),
            fmt, start_ns, end_ns, flatten, batch_rows, index, starts[index],
        )
        for index, (path, counts) in enumerate(zip(paths, held, strict=True))
    )  # fmt: skip
    total = sum(n for counts in held for n in counts.values())
    return Plan(tasks, fmt, total, splits, types)


def prepare_output(out: Path, overwrite: bool) -> None:
    """Create ``out``; an existing one is refused, or with ``overwrite`` replaced.

    Only a directory that holds nothing but ``topic=...`` directories (an export's) is
    removed; anything else there stays, and the export is refused.
    """
    if out.exists() or out.is_symlink():
        if not overwrite:
            raise UsageError(f"{out} exists; refusing to overwrite it", hint="--force replaces it")
        strays = [p.name for p in out.iterdir()] if out.is_dir() and not out.is_symlink() else None
        if strays is None or any(not (out / n).is_dir() or not n.startswith("topic=")
                                 for n in strays):  # fmt: skip
            raise UsageError(f"{out} holds more than an export's topic=... directories; "
                             "refusing to replace it")  # fmt: skip
        shutil.rmtree(out)
    try:
        out.mkdir(parents=True)
    except OSError as err:
        from rostools.errors import cannot_write

        raise cannot_write(out, err.strerror or str(err)) from err


def _start_worker(queue: Any) -> None:
    """In each pool process: where ``export_bag`` counts its rows."""
    dataset._progress_queue = queue


def run_export(
    plan: Plan,
    jobs: int | None = None,
    progress: Callable[[int, int], None] | None = None,
) -> list[BagExport]:
    """Run every task of ``plan``: in this process for one bag or ``jobs`` 1, else a pool."""
    tasks = plan.tasks
    workers = min(jobs or os.cpu_count() or 1, len(tasks))
    done = 0

    def count(rows: int) -> None:
        nonlocal done
        done += rows
        if progress is not None:
            progress(min(done, plan.messages), plan.messages)

    if workers <= 1:
        results = []
        for task in tasks:
            dataset._progress_queue = _Counter(count)
            try:
                results.append(export_bag(task))
            finally:
                dataset._progress_queue = None
        return results
    return _pool(tasks, workers, count)


class _Counter:
    """The progress queue's one method, in this process."""

    def __init__(self, count: Callable[[int], None]) -> None:
        self.count = count

    def put(self, item: tuple[int, int]) -> None:
        self.count(item[1])


def _pool(tasks: Sequence[BagTask], workers: int, count: Callable[[int], None]) -> list[BagExport]:
    import multiprocessing
    import queue as queues
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
    from concurrent.futures.process import BrokenProcessPool

    context = multiprocessing.get_context("spawn")
    rows = context.Queue()

    def drain() -> None:
        while True:
            try:
                count(rows.get_nowait()[1])
            except queues.Empty:
                return

    try:
        with ProcessPoolExecutor(workers, context, initializer=_start_worker,
                                 initargs=(rows,)) as pool:  # fmt: skip
            futures = [pool.submit(export_bag, task) for task in tasks]
            pending = set(futures)
            while pending:
                _, pending = wait(pending, timeout=POLL_PERIOD, return_when=FIRST_COMPLETED)
                drain()
            results = [f.result() for f in futures]
    except BrokenProcessPool as err:
        raise RostoolsError(
            "bag export: a worker process ended without a word (killed, or out of memory?)",
            hint="-j 1 exports one bag at a time, in this process",
        ) from err
    drain()
    return results


def export(
    paths: Sequence[Path],
    out: Path,
    *,
    overwrite: bool = False,
    jobs: int | None = None,
    progress: Callable[[int, int], None] | None = None,
    **options: Any,
) -> ExportReport:
    """Export ``paths`` into the dataset ``out`` (``options``: ``plan_export``'s)."""
    from rostools.bag.tables.arrow import pyarrow

    pyarrow("bag export")  # before anything is written
    out = Path(out)
    plan = plan_export(paths, out, **options)
    prepare_output(out, overwrite)
    results = run_export(plan, jobs, progress)
    return ExportReport(out, plan, tuple(results))
