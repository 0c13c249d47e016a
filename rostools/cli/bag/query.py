"""``rostools bag query "SQL" BAG...``: SQL over bags with DuckDB, each topic a view.

The engine is ``rostools.bag.tables.sql`` (the API's ``bag_sql`` and the plugin's
``assert_sql`` run on it too). Printed as a table (``--format table``, the default), CSV or
NDJSON; every value as DuckDB writes it (its text for a table and CSV, its JSON for JSON).

Bag's quick command (the map's ``query.py`` role): the launcher runs it without Typer, and
duckdb and pyarrow load inside the function, from the ``rostools[sql]`` extra.
"""

from __future__ import annotations

import enum

from rostools.cli import output
from rostools.cli.declare import command
from rostools.errors import one_line

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from pathlib import Path
    from typing import Annotated, Any

    import typer

    from rostools.bag.tables.sql import BagDatabase
    from rostools.cli.bag.options import EndOpt, StartOpt, TopicsOpt
    from rostools.cli.settings import Settings

#: Rows a table shows; the rest are counted and said on stderr (CSV and JSON print them all).
MAX_TABLE_ROWS = 1000
#: Rows fetched from DuckDB at a time for CSV and JSON: memory stays bounded by this.
FETCH_ROWS = 10_000


#: DuckDB's number types: a table aligns them to the right.
NUMERIC = frozenset(
    ("TINYINT", "SMALLINT", "INTEGER", "BIGINT", "HUGEINT", "UTINYINT", "USMALLINT", "UINTEGER",
     "UBIGINT", "UHUGEINT", "FLOAT", "DOUBLE", "DECIMAL")
)  # fmt: skip


class QueryFormat(str, enum.Enum):
    """What ``bag query`` prints."""

    table = "table"
    csv = "csv"
    json = "json"


if TYPE_CHECKING:
    SqlArg = Annotated[
        str, typer.Argument(help='A DuckDB statement; a topic is a table: FROM "/imu".')
    ]
    BagsArg = Annotated[list[Path], typer.Argument(help="Bags (.bag, .mcap).")]
    QueryFormatOpt = Annotated[
        QueryFormat | None,
        typer.Option(
            "--format", "-F", help="table (default), csv or json (NDJSON).", show_default=False
        ),
    ]


@command(quick=True)
def query(
    s: Settings,
    sql: SqlArg,
    bags: BagsArg,
    fmt: QueryFormatOpt = None,
    topics: TopicsOpt = None,
    start: StartOpt = None,
    end: EndOpt = None,
) -> None:
    """Run SQL over bags with DuckDB: each topic is a table named after it ("/imu")."""
    from rostools.bag.tables.sql import connect

    chosen = _format(s, fmt)
    lo, hi = _window(bags, start, end)
    db = connect(bags, topics=topics, start=lo, end=hi)
    try:
        relation = db.sql(sql)
        if relation is not None:  # a statement without rows (CREATE VIEW) prints nothing
            _print(db, relation, chosen)
    finally:
        db.close()


def _window(
    bags: list[Path], start: float | None, end: float | None
) -> tuple[float | None, float | None]:
    """``--start``/``--end`` (from the earliest bag's start) as seconds since the epoch."""
    from rostools.cli.bag.shared import time_window

    lo, hi = time_window(bags, start, end)
    return (None if lo is None else lo / 1e9), (None if hi is None else hi / 1e9)


def _format(s: Settings, fmt: QueryFormat | str | None) -> QueryFormat:
    """The command's ``--format``; else JSON under the global ``--format json``, else a table."""
    if fmt is not None:
        return QueryFormat(fmt)
    return QueryFormat.json if s.format.value == "json" else QueryFormat.table


def _print(db: BagDatabase, relation: Any, fmt: QueryFormat) -> None:
    """The relation's rows in ``fmt``; DuckDB's errors while it runs become ours."""
    import duckdb

    try:
        if fmt is QueryFormat.json:
            _json(relation)
        elif fmt is QueryFormat.csv:
            _csv(relation)
        else:
            _table(relation)
    except duckdb.Error as err:
        raise db.explain(err) from None


def _as_text(relation: Any) -> Any:
    """Every column as DuckDB's text of it (NULL stays NULL), by position: names may repeat."""
    casts = ", ".join(f"CAST(#{i} AS VARCHAR)" for i in range(1, len(relation.columns) + 1))
    return relation.project(casts)


def _rows(relation: Any) -> Any:
    """The relation's rows as tuples, ``FETCH_ROWS`` at a time (Arrow batches from DuckDB)."""
    from rostools.bag.tables.sql import arrow_reader

    for batch in arrow_reader(relation, FETCH_ROWS):
        yield from zip(*(column.to_pylist() for column in batch.columns), strict=True)


def _csv(relation: Any) -> None:
    import csv
    import io

    names = list(relation.columns)
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(names)
    for count, row in enumerate(_rows(_as_text(relation)), 1):
        writer.writerow(["" if v is None else v for v in row])
        if count % FETCH_ROWS == 0:
            output.put(buffer.getvalue())
            buffer.seek(0)
            buffer.truncate()
    output.put(buffer.getvalue())


def _json(relation: Any) -> None:
    """NDJSON: each row an object, as DuckDB's ``to_json`` writes it, NaN as "nan"."""
    import json

    from rostools.msgs.plain import dumps

    # A relation's name in an expression is its whole row, unless a column has that name
    alias = "row"
    while alias in relation.columns:
        alias += "_"
    rows = relation.query(alias, f'SELECT to_json("{alias}") FROM "{alias}"')  # noqa: S608 - our name
    lines: list[str] = []
    for (text,) in _rows(rows):
        # DuckDB writes NaN and Infinity bare, which JSON lacks; Python reads them, and
        # ``dumps`` writes them as every JSON output of rostools does ("nan", "inf").
        lines.append(dumps(json.loads(text)) + "\n")
        if len(lines) >= FETCH_ROWS:
            output.put("".join(lines))
            lines.clear()
    output.put("".join(lines))


def _table(relation: Any) -> None:
    """A table (rich), of the first ``MAX_TABLE_ROWS`` rows."""
    import io
    import shutil
    import sys

    from rich.console import Console
    from rich.markup import escape
    from rich.table import Table

    table = Table()
    for name, kind in zip(relation.columns, relation.types, strict=True):
        # numbers to the right, as DuckDB's own shell aligns them
        right = str(kind).split("(")[0] in NUMERIC
        table.add_column(escape(one_line(name)), justify="right" if right else "left")
    shown = 0
    more = 0
    for row in _rows(_as_text(relation)):
        if shown < MAX_TABLE_ROWS:
            table.add_row(*("NULL" if v is None else escape(one_line(v)) for v in row))
            shown += 1
        else:
            more += 1
    terminal = sys.stdout.isatty()
    # On a terminal the table fits its width, as DuckDB's own; in a pipe it is never cut.
    width = shutil.get_terminal_size().columns if terminal else 1 << 16
    buffer = io.StringIO()
    Console(file=buffer, width=width, force_terminal=terminal, highlight=False).print(table)
    output.put(buffer.getvalue())
    word = "row" if shown + more == 1 else "rows"
    note = f"{shown + more} {word}"
    if more:
        note += f", {more} not shown: --format csv or json prints every row"
    output.flush()
    sys.stderr.write(f"({note})\n")
