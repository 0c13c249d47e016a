"""Bags as Arrow tables for the API: ``bag_table`` and ``bag_batches`` (the extra ``arrow``).

Both read one topic of one or more bags (``.bag`` or MCAP with ROS 1 messages) in time order,
with ``bag/tables/``'s schema: ``record_time``, then the message's fields (docs/tables.md).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from rostools.bag.tables.batches import DEFAULT_BATCH_ROWS, Paths, topic_batches


def bag_batches(
    paths: Paths,
    topic: str,
    *,
    start: float | None = None,
    end: float | None = None,
    batch_rows: int = DEFAULT_BATCH_ROWS,
    flatten: bool = False,
    md5sum: str | None = None,
) -> Any:
    """A streaming ``pyarrow.RecordBatchReader`` over ``topic`` in ``paths`` (one or more bags).

    Memory stays bounded whatever the bags' size: DuckDB, Polars and pandas read it batch by
    batch. ``start``/``end`` are record times in seconds since the epoch (both included);
    ``flatten`` gives dotted column names (``header.stamp``); ``md5sum`` picks one
    definition of a topic recorded with several. Without pyarrow: a ``UsageError`` naming
    ``pip install 'rostools[arrow]'``.
    """
    return topic_batches(
        paths, topic, start=start, end=end, batch_rows=batch_rows, flatten=flatten, md5sum=md5sum
    )


def bag_table(
    paths: str | Path | list[str | Path] | tuple[str | Path, ...],
    topic: str,
    *,
    start: float | None = None,
    end: float | None = None,
    flatten: bool = False,
    md5sum: str | None = None,
) -> Any:
    """``topic``'s messages in ``paths`` as one ``pyarrow.Table`` (``bag_batches``, read whole)."""
    return bag_batches(
        paths, topic, start=start, end=end, flatten=flatten, md5sum=md5sum
    ).read_all()
