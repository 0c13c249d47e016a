"""One bag's part of ``bag export``: its tables, each streamed into one file of the dataset.

``export_bag`` is the unit of work: a function of one picklable ``BagTask`` that returns a
picklable ``BagExport``, so any pool of processes runs it: ours (``export.py``), or Dask's
distributed scheduler (``client.map(export_bag, tasks)``). It touches no state but the files
it writes; the only thing it reports on the way is its progress, to a queue our pool sets.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final

import numpy as np

from rostools.bag.tables.arrow import from_numpy, repeated_string
from rostools.bag.tables.batches import DEFAULT_BATCH_ROWS
from rostools.bag.tables.layout import bag_key, part_path
from rostools.bag.tables.writers import FORMATS, open_table

if TYPE_CHECKING:
    import pyarrow as pa

#: Rows per record batch (``topic_batches``'s): memory is about one batch of each bag under way.
BATCH_ROWS: Final = DEFAULT_BATCH_ROWS

#: ``topic_batches`` takes seconds as floats, a few hundred ns coarse at today's times: it is
#: asked for this much more on each side, and ``_within`` cuts at the exact ns.
_SLACK_NS: Final = 1_000_000

#: What ``lost_data`` writes before the damage it lists.
LEFT_OUT: Final = "left out what could not be read: "

#: Our pool's progress queue in a worker (``export.py`` sets it); None under Dask.
_progress_queue: Any = None


@dataclass(frozen=True)
class TableChoice:
    """One table to write from a bag: a topic, the definition (md5sum) and its key."""

    topic: str
    md5sum: str
    key: str


@dataclass(frozen=True)
class BagTask:
    """Everything ``export_bag`` needs for one bag: plain values, so it pickles.

    ``start_ns``/``end_ns`` bound the record times (absolute ns, None: no bound).
    ``bag_start_ns`` is the bag's first record time, from its index (None: read it here).
    """

    path: str
    out: str
    tables: tuple[TableChoice, ...]
    format: str = "parquet"
    start_ns: int | None = None
    end_ns: int | None = None
    flatten: bool = False
    batch_rows: int = BATCH_ROWS
    index: int = 0
    bag_start_ns: int | None = None


@dataclass(frozen=True)
class WrittenFile:
    """One file written: the table it belongs to, its path under OUT and its rows."""

    key: str
    topic: str
    md5sum: str
    file: str
    rows: int


@dataclass(frozen=True)
class BagExport:
    """What ``export_bag`` did with one bag: its files, and what it could not read."""

    path: str
    files: tuple[WrittenFile, ...] = ()
    lost: tuple[str, ...] = ()
    skipped: tuple[tuple[str, int], ...] = ()  # (the one line, its exit code)


def _say_progress(index: int, rows: int) -> None:
    if _progress_queue is not None:
        _progress_queue.put((index, rows))


def bag_columns(pa: Any, batch: pa.RecordBatch, name: str, start_ns: int | None) -> Any:
    """``batch`` with the bag's name and start time as two more columns.

    The start time has the type of ``record_time`` (a timestamp in ns), so the two compare.
    """
    rows = batch.num_rows
    kind = batch.schema.field("record_time").type
    schema = batch.schema.append(pa.field("bag_name", pa.string())).append(
        pa.field("bag_start", kind)
    )
    starts = from_numpy(pa, np.full(rows, start_ns, np.int64), kind)
    # from_arrays, not append_column: pyarrow 14 (the extra's floor) has no such method
    columns = [*batch.columns, repeated_string(pa, name, rows), starts]
    return pa.RecordBatch.from_arrays(columns, schema=schema)


def export_bag(task: BagTask) -> BagExport:
    """Write each of ``task``'s tables from its bag into the dataset at ``task.out``.

    A table with no row in the time range gets no file. What the bag's damage left out is
    in ``lost``, a table that could not be read (a type the bag does not define, a message
    that does not fit its type) in ``skipped``: the rows that could be read are written all
    the same.
    """
    from rostools.bag.tables.arrow import pyarrow
    from rostools.errors import DataLossError, RostoolsError

    pa = pyarrow("bag export")
    files: list[WrittenFile] = []
    lost: list[str] = []
    skipped: list[tuple[str, int]] = []
    for table in task.tables:
        try:
            _write_table(pa, task, table, files)
        except DataLossError as err:
            # The bag's damage, said once for all its tables (each topic's read meets it).
            what = f"{task.path}: {str(err).partition(LEFT_OUT)[2] or err}"
            if what not in lost:
                lost.append(what)
        except RostoolsError as err:
            skipped.append((str(err), err.exit_code))
    return BagExport(task.path, tuple(files), tuple(lost), tuple(skipped))


def _write_table(pa: Any, task: BagTask, table: TableChoice, files: list[WrittenFile]) -> None:
    """One table of one bag into its file; the file, once opened, is listed in ``files``."""
    path = Path(task.path)
    target = part_path(Path(task.out), table.key, bag_key(path), FORMATS[task.format])
    start_ns = task.bag_start_ns
    writer = None
    rows = 0
    try:
        for batch in _batches(task, table):
            if task.start_ns is not None or task.end_ns is not None:
                batch = _within(pa, batch, task.start_ns, task.end_ns)
            if batch.num_rows == 0:
                continue
            if start_ns is None:
                from rostools.bag.formats.access import bag_info

                start_ns = bag_info(path).start_ns
            batch = bag_columns(pa, batch, path.name, start_ns)
            if writer is None:
                writer = open_table(task.format, target, batch.schema)
            writer.write(batch)
            rows += batch.num_rows
            _say_progress(task.index, batch.num_rows)
    finally:
        if writer is not None:
            writer.close()
            relative = str(target.relative_to(task.out))
            files.append(WrittenFile(table.key, table.topic, table.md5sum, relative, rows))


def _batches(task: BagTask, table: TableChoice) -> Any:
    """The record batches of one table of one bag (``topic_batches``, bounded)."""
    from rostools.bag.tables.batches import topic_batches

    start = None if task.start_ns is None else (task.start_ns - _SLACK_NS) / 1e9
    end = None if task.end_ns is None else (task.end_ns + _SLACK_NS) / 1e9
    return topic_batches(
        [task.path], table.topic, start=start, end=end,
        batch_rows=task.batch_rows, flatten=task.flatten, md5sum=table.md5sum,
    )  # fmt: skip


def _within(pa: Any, batch: Any, lo: int | None, hi: int | None) -> Any:
    """The rows of ``batch`` recorded from ``lo`` to ``hi`` ns, both included, exactly."""
    import pyarrow.compute as pc

    t = batch.column("record_time").cast(pa.int64())
    keep = pc.and_(
        pc.greater_equal(t, lo if lo is not None else t),
        pc.less_equal(t, hi if hi is not None else t),
    )
    return batch.filter(keep)
