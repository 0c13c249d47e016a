"""The pytest plugin's ``assert_sql`` (issue 38): a recording checked with SQL, run by pytester.

A pass returns the rows; a failure shows the test's line, the query, what was expected and
the rows it gave, and no rostools frames; bad SQL is DuckDB's one line.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.integration.test_cli_bag_query import IMU_COUNT, write_imu

pytest.importorskip("duckdb", reason="the test extra installs duckdb (rostools[sql])")
pytest_plugins = ["pytester"]


def test_assert_sql_passes_and_fails_readably(pytester: pytest.Pytester, tmp_path: Path) -> None:
    bag = write_imu(tmp_path / "imu.bag")
    pytester.makepyfile(
        test_recorded=f"""
        import pytest
        from rostools.testing import assert_sql

        BAG = {str(bag)!r}

        def test_one_value():
            rows = assert_sql(BAG, 'SELECT max(linear_acceleration.z) FROM "/imu"', 2.75)
            assert rows == [(2.75,)]

        def test_rows_and_approx():
            first = 'SELECT header.seq, linear_acceleration.z FROM "/imu" ORDER BY 1 LIMIT 2'
            assert_sql(BAG, first, [(0, 0.0), (1, 0.25)])
            assert_sql([BAG], 'SELECT avg(linear_acceleration.z) FROM "/imu"', pytest.approx(1.375))

        def test_a_value_that_differs():
            assert_sql(BAG, 'SELECT count(*) FROM "/imu"', 13)

        def test_bad_sql():
            assert_sql(BAG, 'SELECT nope FROM "/imu"')

        def test_a_topic_not_there():
            assert_sql(BAG, 'SELECT count(*) FROM "/odom"', 0)
        """
    )
    result = pytester.runpytest_inprocess("-p", "no:cacheprovider")
    result.assert_outcomes(passed=2, failed=3)
    result.stdout.fnmatch_lines(
        [
            """>       assert_sql(BAG, 'SELECT count(*) FROM "/imu"', 13)""",
            'E       AssertionError: SELECT count(*) FROM "/imu"',
            "E       expected: 13",
            "E       got 1 row(s):",
            f"E         ({IMU_COUNT},)",
            "test_recorded.py:*: AssertionError",
            """>       assert_sql(BAG, 'SELECT nope FROM "/imu"')""",
            'E       rostools.errors.UsageError: Binder Error: Referenced column "nope" not found*',
            "test_recorded.py:*: UsageError",
            """>       assert_sql(BAG, 'SELECT count(*) FROM "/odom"', 0)""",
            "E       rostools.errors.NotFoundError: no topic /odom in the bags:*",
        ]
    )
    shown = [line for line in result.outlines if "rostools/" in line and ".py:" in line]
    assert not shown, shown
