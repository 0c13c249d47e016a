"""``bag/tables/sql.py`` without a bag: which DuckDB it accepts (issue 38)."""

from __future__ import annotations

import pytest

from rostools.bag.tables import sql
from rostools.errors import UsageError

duckdb = pytest.importorskip("duckdb", reason="the test extra installs duckdb (rostools[sql])")


def test_a_duckdb_before_1_5_is_one_line_naming_the_upgrade(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """Before 1.5 DuckDB reads a view's stream once: a self-join would fail inside DuckDB."""
    monkeypatch.setattr(duckdb, "__version__", "1.4.1")
    with pytest.raises(UsageError) as caught:
        sql.duckdb_module("bag query")
    assert str(caught.value) == (
        "bag query needs duckdb 1.5 or later, not 1.4.1: pip install -U 'rostools[sql]'"
    )
    for newer in ("1.5.0", "1.10.2", "2.0.1", "2.1.0.dev12"):
        monkeypatch.setattr(duckdb, "__version__", newer)
        assert sql.duckdb_module() is duckdb
