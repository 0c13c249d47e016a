"""Bags as Arrow tables for the API: ``bag_table`` and ``bag_batches`` (the extra ``arrow``).

Both read one topic of one or more bags (``.bag`` or MCAP with ROS 1 messages) in time order,
with ``bag/tables/``'s schema: ``record_time``, then the message's fields (docs/tables.md).
``bag_batches`` is ``bag/tables/batches.topic_batches`` itself: a streaming
``pyarrow.RecordBatchReader`` that DuckDB, Polars and pandas read batch by batch.
"""

from __future__ import annotations

from typing import Any

from rostools.bag.tables.batches import Paths, topic_batches

bag_batches = topic_batches


def bag_table(
    paths: Paths,
    topic: str,
    *,
    start: float | None = None,
    end: float | None = None,
    flatten: bool = False,
    md5sum: str | None = None,
) -> Any:
    """``topic``'s messages in ``paths`` as one ``pyarrow.Table`` (``bag_batches``, read whole).

    ``start``/``end``: record times in seconds since the epoch, both included; ``flatten``:
    dotted column names (``header.stamp``); ``md5sum``: one definition of a topic recorded
    with several. Without pyarrow: a ``UsageError`` naming ``pip install 'rostools[arrow]'``.
    """
    return topic_batches(
        paths, topic, start=start, end=end, flatten=flatten, md5sum=md5sum
    ).read_all()
