"""SQL over bags with DuckDB: each topic a view over Arrow record batches (``bag query``).

One engine for the command, the API (``rostools.bag_sql``) and the pytest plugin
(``rostools.testing.assert_sql``): ``connect`` opens an in-memory DuckDB with one view per
topic of the bags, named after the topic (``"/imu"``), and ``bag_sql`` runs a statement on it.

Every topic is registered, so ``SHOW TABLES`` and ``DESCRIBE "/imu"`` answer, but nothing is
decoded until DuckDB scans it: a view is a ``TopicSource``, which gives DuckDB its schema at
once and a fresh stream of record batches (``topic_batches``) each time a query reads it (the
Arrow PyCapsule interface). ``SELECT count(*) FROM "/imu"`` decodes ``/imu`` alone, a self-join
reads it twice, a ``LIMIT`` stops reading early, and nothing is written to disk first.

duckdb and pyarrow are imported inside functions: the base install neither needs nor loads
them (``rostools[sql]``).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rostools.errors import MissingExtraError, NotFoundError, RostoolsError, UsageError

if TYPE_CHECKING:
    from collections.abc import Sequence

    from rostools.bag.tables.batches import TopicTable

#: The first DuckDB that scans a ``TopicSource`` anew each time a query reads it; before 1.5 a
#: PyCapsule object is read once (a self-join fails, 1.4 reads it as it is registered).
MIN_DUCKDB = (1, 5)
#: Messages a view hands DuckDB at a time. DuckDB works on 2,048 rows at once; batches smaller
#: than ``topic_batches``' default keep the peak down (a 200,000-Imu bag's count: 320 MB at
#: 65,536 rows, 240 MB at this) and cost no time.
BATCH_ROWS = 16_384
#: DuckDB's words for a table that is not there (``Catalog Error: Table with name x does not
#: exist!``), as its 0.10 to 1.x and 2.x releases write them.
_NO_TABLE = re.compile(r"Table with name (.+?) does not exist")


def duckdb_module(what: str = "") -> Any:
    """The ``duckdb`` module, or a ``MissingExtraError`` naming ``rostools[sql]`` (exit 2)."""
    try:
        import duckdb
    except ImportError:
        raise MissingExtraError("duckdb", "sql", what=what) from None
    if _older(duckdb.__version__, MIN_DUCKDB):
        need = ".".join(map(str, MIN_DUCKDB))
        raise UsageError(
            f"{what or 'rostools'} needs duckdb {need} or later, not {duckdb.__version__}:"
            " pip install -U 'rostools[sql]'"
        )
    return duckdb


def _older(version: str, than: tuple[int, int]) -> bool:
    """Whether a ``major.minor...`` version string is older than ``than``."""
    numbers = [int(m) for m in re.findall(r"\d+", version)[:2]]
    return tuple(numbers) < than


class TopicSource:
    """One topic of the bags as DuckDB reads it: its schema now, its batches when scanned.

    DuckDB asks ``__arrow_c_schema__`` to bind a query and ``__arrow_c_stream__`` once per
    scan, so a topic no query reads is never decoded. An error of ours raised while DuckDB
    scans (a damaged bag) reaches DuckDB as its own exception and loses its exit code: it is
    kept in ``failure`` for ``bag_sql`` to raise instead.
    """

    def __init__(
        self,
        paths: Sequence[Path],
        table: TopicTable,
        start: float | None,
        end: float | None,
    ) -> None:
        self.paths = list(paths)
        self.table = table
        self.start = start
        self.end = end
        self.failure: RostoolsError | None = None

    def __arrow_c_schema__(self) -> object:
        """The Arrow schema's PyCapsule: what DuckDB binds a query against."""
        return self.table.schema.__arrow_c_schema__()

    def __arrow_c_stream__(self, requested_schema: object = None) -> object:
        """A new stream of the topic's record batches, for one scan."""
        import pyarrow as pa

        from rostools.bag.tables.batches import topic_batches

        reader = topic_batches(
            self.paths, self.table.topic, start=self.start, end=self.end,
            md5sum=self.table.md5sum, batch_rows=BATCH_ROWS,
        )  # fmt: skip

        def guarded() -> Any:
            try:
                yield from reader
            except RostoolsError as err:
                self.failure = err
                raise

        stream = pa.RecordBatchReader.from_batches(reader.schema, guarded())
        return stream.__arrow_c_stream__(requested_schema)


def arrow_table(relation: Any) -> Any:
    """A DuckDB relation's rows as a ``pyarrow.Table`` (``to_arrow_table`` from DuckDB 1.4 on)."""
    fetch = getattr(relation, "to_arrow_table", None) or relation.fetch_arrow_table
    return fetch()


def arrow_reader(relation: Any, rows: int) -> Any:
    """A DuckDB relation's rows as a ``pyarrow.RecordBatchReader`` of batches of ``rows``."""
    fetch = getattr(relation, "to_arrow_reader", None) or relation.fetch_record_batch
    return fetch(rows)


class BagDatabase:
    """An in-memory DuckDB connection with a view per topic of the bags (``connect``)."""

    def __init__(
        self,
        connection: Any,
        sources: dict[str, TopicSource],
        unreadable: dict[str, str] | None = None,
    ) -> None:
        #: The DuckDB connection: ``connection.sql(...)`` as DuckDB's own.
        self.connection = connection
        #: Each view's name and the topic it reads.
        self.sources = sources
        #: Tables the bags hold but that cannot be read (``TopicTable.error``): no view; a
        #: query that names one gets that error.
        self.unreadable = unreadable or {}

    def sql(self, statement: str) -> Any:
        """Run ``statement``: its ``DuckDBPyRelation`` (None for one that returns no rows).

        DuckDB's errors become ours, one line each: a table that is not there is a
        ``NotFoundError`` naming the bags' topics (exit 3), any other SQL error a
        ``UsageError`` with DuckDB's message (exit 2).
        """
        duckdb = duckdb_module()
        try:
            return self.connection.sql(statement)
        except duckdb.Error as err:
            raise self.explain(err) from None

    def table(self, statement: str) -> Any:
        """Run ``statement`` to its end: a ``pyarrow.Table`` (empty for one without rows)."""
        import pyarrow as pa

        duckdb = duckdb_module()
        relation = self.sql(statement)
        if relation is None:
            return pa.table({})
        try:
            return arrow_table(relation)
        except duckdb.Error as err:
            raise self.explain(err) from None

    def explain(self, err: Exception) -> RostoolsError:
        """Our error for a DuckDB one raised by a query on these views."""
        for source in self.sources.values():
            if source.failure is not None:
                return source.failure
        text = str(err).strip()
        missing = _NO_TABLE.search(text)
        if missing:
            topics = ", ".join(f'"{name}"' for name in sorted(self.sources)) or "none"
            name = missing.group(1)
            if name in self.unreadable:
                return NotFoundError(self.unreadable[name])
            hint = None if "/" in name else 'a topic is a quoted name: SELECT * FROM "/imu"'
            return NotFoundError(f"no topic {name} in the bags: they hold {topics}", hint=hint)
        # DuckDB's first line says it all; the lines after it echo the statement with a caret
        return UsageError(text.partition("\n")[0])

    def close(self) -> None:
        """Close the connection."""
        self.connection.close()


def connect(
    paths: Sequence[str | Path],
    *,
    topics: Sequence[str] | None = None,
    start: float | None = None,
    end: float | None = None,
) -> BagDatabase:
    """An in-memory DuckDB with one view per topic of ``paths`` (or of ``topics``).

    ``start`` and ``end`` are record times in seconds since the epoch, both included, as
    ``topic_batches`` takes them. A topic whose definition changes between bags has a view
    per definition, named as ``TopicTable.name`` says (``/imu@0123abcd``).
    """
    duckdb = duckdb_module("bag query")
    from rostools.bag.tables.batches import table_schemas

    files = [Path(p) for p in paths]
    tables = table_schemas(files, list(topics) if topics else None)
    if topics:
        missing = sorted(set(topics) - {t.topic for t in tables})
        if missing:
            there = ", ".join(sorted({t.topic for t in table_schemas(files, None)})) or "none"
            raise NotFoundError(f"no topic {', '.join(missing)} in the bags: they hold {there}")
    connection = duckdb.connect(":memory:")
    sources: dict[str, TopicSource] = {}
    unreadable: dict[str, str] = {}
    for table in tables:
        if table.error is not None:  # a type the bag does not define: said if a query names it
            unreadable[table.name] = table.error
            continue
        source = TopicSource(files, table, start, end)
        connection.register(table.name, source)
        sources[table.name] = source
    return BagDatabase(connection, sources, unreadable)


def bag_sql(
    sql: str,
    paths: str | Path | Sequence[str | Path],
    *,
    topics: Sequence[str] | None = None,
    start: float | None = None,
    end: float | None = None,
) -> Any:
    """Run ``sql`` over bags, each topic a view named after it: the result, a ``pyarrow.Table``.

    ``bag_sql('SELECT avg(linear_acceleration.z) FROM "/imu"', "run.bag")`` decodes ``/imu``
    alone. The table goes on to pandas (``.to_pandas()``) or Polars (``pl.from_arrow``).
    ``topics`` limits the views; ``start`` and ``end`` are record times in seconds since the
    epoch, as ``bag_table`` takes them. Errors are rostools' (a missing extra or bad SQL:
    ``UsageError``, exit 2; a topic the bags lack: ``NotFoundError``, exit 3), raised whether
    DuckDB finds them as it reads the statement or as it runs it.
    """
    files = [paths] if isinstance(paths, str | Path) else list(paths)
    db = connect(files, topics=topics, start=start, end=end)
    try:
        return db.table(sql)
    finally:
        db.close()
