"""Assertions on a recording with SQL: ``assert_sql(bag, 'SELECT max(...) FROM "/odom"', 0.5)``.

The query runs as ``rostools bag query`` runs it (``rostools.bag.tables.sql``: each topic a
DuckDB view named after it), so a query tried on the command line reads the same here. Needs
``rostools[sql]``; a failure shows the query, what was expected and the rows it gave.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from rostools.testing.readable import readable

#: Rows a failure shows of a result.
SHOWN_ROWS = 10


def _scalar(rows: list[tuple[Any, ...]]) -> bool:
    return len(rows) == 1 and len(rows[0]) == 1


def _shown(rows: list[tuple[Any, ...]]) -> str:
    lines = [f"  {row!r}" for row in rows[:SHOWN_ROWS]]
    if len(rows) > SHOWN_ROWS:
        lines.append(f"  ... {len(rows) - SHOWN_ROWS} more")
    return "\n".join(lines) if lines else "  (no rows)"


@readable
def assert_sql(
    bags: str | Path | Sequence[str | Path],
    sql: str,
    expected: Any = None,
    *,
    topics: Sequence[str] | None = None,
    start: float | None = None,
    end: float | None = None,
) -> list[tuple[Any, ...]]:
    """Run ``sql`` over ``bags`` and check its result; the rows, as tuples.

    ``expected`` is the rows (a list of tuples), or, for a result of one row of one column
    (``SELECT max(twist.twist.linear.x) FROM "/odom"``), that one value; ``pytest.approx``
    works for either. None checks only that the query runs. Values are DuckDB's Python ones:
    a ``time`` column is a ``datetime``, a struct a ``dict``, a list a ``list``.
    """
    __tracebackhide__ = True
    from rostools.bag.tables.sql import connect

    files = [bags] if isinstance(bags, str | Path) else list(bags)
    db = connect(files, topics=topics, start=start, end=end)
    try:
        rows = _fetch(db, sql)
    finally:
        db.close()
    if expected is None:
        return rows
    got: Any = rows[0][0] if _scalar(rows) and not isinstance(expected, list) else rows
    if got != expected:
        raise AssertionError(
            f"{sql}\nexpected: {expected!r}\ngot {len(rows)} row(s):\n{_shown(rows)}"
        )
    return rows


def _fetch(db: Any, sql: str) -> list[tuple[Any, ...]]:
    """Every row of ``sql``, with DuckDB's errors as ours (``readable`` shows their line)."""
    import duckdb

    relation = db.sql(sql)
    if relation is None:
        return []
    try:
        return list(relation.fetchall())
    except duckdb.Error as err:
        raise db.explain(err) from None
