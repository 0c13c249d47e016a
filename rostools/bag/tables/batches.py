"""A topic of one or more bags as a stream of Arrow record batches, and what tables bags hold.

``table_schemas`` lists the tables: one per (topic, md5sum), since a topic whose definition
changes between bags cannot be one table. ``topic_batches`` streams one of them in time order
across the bags (``merged_messages``), decoding the raw bytes of a batch straight into columns
(``columns.py``); memory is bounded by a batch (``batch_rows`` messages or ``BATCH_BYTES``).
"""

from __future__ import annotations

from collections.abc import Iterable, Iterator, Sequence
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

import numpy as np

from rostools.bag.formats.access import merged_messages, open_bag, require_ros1
from rostools.bag.formats.base import BagReader
from rostools.bag.formats.model import NS_PER_SEC, Connection, lost_data
from rostools.bag.formats.runs import Run, runs_of
from rostools.bag.tables.arrow import from_numpy, pyarrow
from rostools.bag.tables.columns import ColumnDecoder
from rostools.bag.tables.schema import flat_arrays, table_schema
from rostools.bag.tables.uniform import fill_uniform
from rostools.errors import InvalidDataError, NotFoundError, RostoolsError, UsageError
from rostools.msgs import learnt
from rostools.msgs.codec import DECODE_ERRORS, DecodeError, why_not
from rostools.msgs.store import TypeStore

#: Messages per record batch unless the caller says (Arrow's engines like batches of 10^4-10^6).
DEFAULT_BATCH_ROWS: Final = 65536
#: A batch ends once its messages hold this many bytes, whatever ``batch_rows`` says: what
#: bounds memory with big messages (point clouds, images). Under glibc's largest mmap
#: threshold (32 MiB), so a batch's buffers are reused, not mapped afresh and faulted in: 64
#: MiB batches took half again as long to export point clouds.
BATCH_BYTES: Final = 16 << 20

Paths = Sequence[str | Path] | str | Path


@dataclass(frozen=True)
class TopicTable:
    """One table the bags hold: a topic's messages of one definition (md5sum).

    ``name`` is how a caller names it: the topic, or, when the bags hold the topic with more
    than one definition, ``TOPIC@MD5`` (the md5sum's first 8 hex digits), one per definition;
    ``topic_batches(paths, topic, md5sum=md5sum)`` reads it. ``schema`` is the Arrow schema
    of its batches (nested; ``flatten=True`` gives ``flat_schema`` of it). A table that cannot
    be read (a type the bag does not define and no store knows) has no schema and ``error``
    says why in one line; ``topic_batches`` raises that error.
    """

    name: str
    topic: str
    type: str
    md5sum: str
    schema: Any
    messages: int
    error: str | None = None


def _paths(paths: Paths) -> list[Path]:
    if isinstance(paths, str | Path):
        return [Path(paths)]
    return [Path(p) for p in paths]


def _readers(
    stack: ExitStack, paths: Paths, what: str, topics: Sequence[str] | None
) -> list[BagReader]:
    found = _paths(paths)
    if not found:
        raise UsageError(f"{what}: no bag given")
    readers = [stack.enter_context(open_bag(p)) for p in found]
    for reader in readers:
        require_ros1(reader, what, topics)
    return readers


def _decoder(conns: list[Connection]) -> ColumnDecoder:
    """The column decoder of connections of one md5sum (the first full definition wins)."""
    conn = next((c for c in conns if c.definition.strip()), conns[0])
    try:
        codec = learnt.codec(TypeStore.default(), conn.type, conn.md5sum, conn.definition)
        return ColumnDecoder(codec, conn.type)  # a stream's own: its columns are its state
    except NotFoundError as err:
        raise NotFoundError(
            f"{conn.topic}: {err}; the bag does not define it (ROSTOOLS_MSG_PATH can)"
        ) from None


def _by_md5(
    readers: list[BagReader], topics: Sequence[str] | None
) -> dict[tuple[str, str], list[Connection]]:
    groups: dict[tuple[str, str], list[Connection]] = {}
    for reader in readers:
        for conn in reader.connections:
            if topics is None or conn.topic in topics:
                groups.setdefault((conn.topic, conn.md5sum), []).append(conn)
    return groups


def table_schemas(paths: Paths, topics: Sequence[str] | None = None) -> list[TopicTable]:
    """The tables these bags hold, by topic then first appearance: one per (topic, md5sum)."""
    with ExitStack() as stack:
        readers = _readers(stack, paths, "table_schemas", topics)
        counts: dict[tuple[str, str], int] = {}
        for reader in readers:
            per_conn = reader.info().connection_counts
            for conn in reader.connections:
                key = (conn.topic, conn.md5sum)
                counts[key] = counts.get(key, 0) + per_conn.get(conn.id, 0)
        groups = _by_md5(readers, topics)
    definitions: dict[str, int] = {}
    for topic, _ in groups:
        definitions[topic] = definitions.get(topic, 0) + 1
    tables = []
    for (topic, md5sum), conns in sorted(groups.items(), key=lambda kv: kv[0][0]):
        name = topic if definitions[topic] == 1 else f"{topic}@{md5sum[:8]}"
        schema, error = None, None
        try:
            schema = table_schema(_decoder(conns).fields)
        except RostoolsError as err:  # one table that cannot be read does not hide the others
            error = str(err)
        tables.append(
            TopicTable(name, topic, conns[0].type, md5sum, schema, counts[(topic, md5sum)], error)
        )
    return tables


def topic_batches(
    paths: Paths,
    topic: str,
    *,
    start: float | None = None,
    end: float | None = None,
    batch_rows: int = DEFAULT_BATCH_ROWS,
    flatten: bool = False,
    md5sum: str | None = None,
) -> Any:
    """A ``pyarrow.RecordBatchReader`` over ``topic``'s messages in these bags, in time order.

    ``start``/``end``: record times in seconds since the epoch, both included. ``md5sum``
    picks one definition of a topic the bags hold with several (``table_schemas`` lists
    them); without it such a topic is a ``UsageError`` naming them. ``flatten``: dotted
    column names for nested messages (``header.stamp``); arrays stay lists. Memory stays
    bounded: a batch is ``batch_rows`` messages or ``BATCH_BYTES`` of them. The bags stay open
    until the reader is exhausted or closed. Without pyarrow: ``MissingExtraError`` (exit 2)
    naming ``pip install 'rostools[arrow]'``.
    """
    pa = pyarrow("bag tables")
    if batch_rows < 1:
        raise UsageError(f"batch_rows must be at least 1, not {batch_rows}")
    stack = ExitStack()
    try:
        readers = _readers(stack, paths, "bag tables", [topic])
        groups = {md5: conns for (_, md5), conns in _by_md5(readers, [topic]).items()}
        if not groups:
            names = ", ".join(str(r.path) for r in readers)
            raise NotFoundError(f"topic {topic} is not in {names}")
        if md5sum is None and len(groups) > 1:
            raise UsageError(
                f"{topic} has {len(groups)} definitions in these bags (md5sums "
                f"{', '.join(sorted(groups))}): pick one with md5sum"
            )
        chosen = md5sum or next(iter(groups))
        if chosen not in groups:
            raise NotFoundError(f"topic {topic} has no messages of md5sum {chosen}")
        decoder = _decoder(groups[chosen])
        schema = table_schema(decoder.fields, flatten=flatten)
    except BaseException:
        stack.close()
        raise
    lo = None if start is None else round(start * NS_PER_SEC)
    hi = None if end is None else round(end * NS_PER_SEC)
    stream = _batches(stack, readers, topic, chosen, decoder, schema, (lo, hi), batch_rows, flatten)
    return pa.RecordBatchReader.from_batches(schema, stream)


def _batches(
    stack: ExitStack,
    readers: list[BagReader],
    topic: str,
    md5sum: str,
    decoder: ColumnDecoder,
    schema: Any,
    window: tuple[int | None, int | None],
    batch_rows: int,
    flatten: bool,
) -> Iterator[Any]:
    pa = pyarrow()
    count = 0
    with stack:
        if len(readers) == 1:  # one bag is in time order already: read a chunk at a time
            reader = readers[0]
            chosen = [c for c in reader.connections if c.topic == topic and c.md5sum == md5sum]
            runs = reader.runs(chosen, *window)
        else:
            merged = merged_messages(readers, [topic], *window)
            runs = runs_of(m for m in merged if m[0].md5sum == md5sum)
        for parts in _cut(runs, batch_rows):
            count += sum(map(len, parts))
            yield _batch(pa, decoder, parts, topic, schema, flatten)
        damage = [d for r in readers for d in r.damage]
        if damage:
            raise lost_data(f"read {count} messages of {topic}", damage)


def _cut(runs: Iterable[Run], batch_rows: int) -> Iterator[list[Run]]:
    """Runs of messages regrouped into batches of ``batch_rows`` messages, each a list of runs.

    A batch ends sooner once it holds ``BATCH_BYTES``: the message that reaches it is its last.
    """
    parts: list[Run] = []
    rows = size = 0
    for run in runs:
        ends = np.cumsum(run.sizes())
        i = 0
        while i < len(run):
            before = int(ends[i - 1]) if i else 0
            n = min(len(run) - i, batch_rows - rows)
            full = int(np.searchsorted(ends[i : i + n] - before, BATCH_BYTES - size))
            n = min(n, full + 1)
            parts.append(run if n == len(run) else run.part(i, i + n))
            rows, size, i = rows + n, size + int(ends[i + n - 1]) - before, i + n
            if rows >= batch_rows or size >= BATCH_BYTES:
                yield parts
                parts, rows, size = [], 0, 0
    if rows:
        yield parts


def _fill(decoder: ColumnDecoder, parts: list[Run], topic: str) -> None:
    """The batch into the decoder's columns: in one go when it can, else message by message."""
    if fill_uniform(decoder, parts):
        return
    fill = decoder.fill
    for part in parts:
        for t_ns, data in zip(part.times.tolist(), part.data(), strict=True):
            try:
                fill(data)
            except (DecodeError, *DECODE_ERRORS) as err:
                decoder.clear()
                raise InvalidDataError(
                    f"{topic}: the message recorded at {t_ns / NS_PER_SEC:.9f} is not a"
                    f" {decoder.type_name}: {why_not(err)}"
                ) from None


def _batch(
    pa: Any, decoder: ColumnDecoder, parts: list[Run], topic: str, schema: Any, flatten: bool
) -> Any:
    _fill(decoder, parts, topic)
    rows = sum(map(len, parts))
    arrays = decoder.finish(rows)
    if flatten:
        arrays = flat_arrays(arrays, decoder.fields)
    times = np.concatenate([part.times for part in parts])
    stamps = from_numpy(pa, times, pa.timestamp("ns"))
    return pa.RecordBatch.from_arrays([stamps, *arrays], schema=schema)
