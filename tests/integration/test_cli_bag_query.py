"""``bag query`` (issue 38): SQL over bags with DuckDB, each topic a view named after it.

The answers are checked against values computed apart from DuckDB: from the messages a test
wrote (Python arithmetic) and, for a corpus bag, from ``topic_batches`` with pyarrow.compute.
"""

from __future__ import annotations

import csv
import io
import json
import struct
import subprocess
import sys
from collections import defaultdict
from datetime import datetime, timezone
from pathlib import Path

import pytest

from rostools.bag.formats.access import open_writer
from rostools.msgs.store import TypeStore
from tests.support.bagdata import write_sample
from tests.support.env import CORPUS, needs_corpus, run_cli

pa = pytest.importorskip("pyarrow", reason="the test extra installs pyarrow (rostools[arrow])")
duckdb = pytest.importorskip("duckdb", reason="the test extra installs duckdb (rostools[sql])")

#: The issue's example, verbatim.
EXAMPLE = (
    "SELECT date_trunc('second', header.stamp) AS s, avg(linear_acceleration.z) "
    'FROM "/imu" GROUP BY s'
)
#: Imu messages: three a second from t = 1.7e9 s, for four seconds; z = i / 4.
IMU_COUNT = 12
START_S = 1_700_000_000


def _imu(i: int) -> bytes:
    """sensor_msgs/Imu number ``i``: header.stamp 1/3 s apart, linear_acceleration.z = i / 4."""
    secs, nsecs = START_S + i // 3, (i % 3) * 333_333_333
    frame = b"imu_link"
    header = struct.pack("<3I", i, secs, nsecs) + struct.pack("<I", len(frame)) + frame
    covariance = struct.pack("<9d", *([0.0] * 9))
    orientation = struct.pack("<4d", 0.0, 0.0, 0.0, 1.0)
    angular = struct.pack("<3d", 0.1, 0.2, 0.3)
    linear = struct.pack("<3d", 0.0, float(i), i / 4)
    return header + orientation + covariance + angular + covariance + linear + covariance


def _stamp_ns(i: int) -> int:
    return (START_S + i // 3) * 10**9 + (i % 3) * 333_333_333


def write_imu(path: Path) -> Path:
    """A bag of ``IMU_COUNT`` Imu messages on /imu, recorded 1 ms after each stamp, and /count."""
    store = TypeStore.default()
    with open_writer(path) as writer:
        imu = writer.add_connection(
            "/imu", "sensor_msgs/Imu", store.md5("sensor_msgs/Imu"),
            store.full_text("sensor_msgs/Imu"), callerid="/imu_node",
        )  # fmt: skip
        count = writer.add_connection(
            "/count", "std_msgs/Int32", store.md5("std_msgs/Int32"), "int32 data\n",
            callerid="/counter",
        )  # fmt: skip
        for i in range(IMU_COUNT):
            writer.write(imu, _stamp_ns(i) + 10**6, _imu(i))
            writer.write(count, _stamp_ns(i) + 2 * 10**6, struct.pack("<i", i))
    return path


def expected_per_second() -> dict[str, float]:
    """The issue example's answer, from the values written: second (DuckDB's text) -> mean z."""
    groups: dict[str, list[float]] = defaultdict(list)
    for i in range(IMU_COUNT):
        second = datetime.fromtimestamp(START_S + i // 3, timezone.utc)
        groups[second.strftime("%Y-%m-%d %H:%M:%S")].append(i / 4)
    return {k: sum(v) / len(v) for k, v in groups.items()}


@pytest.fixture(scope="module")
def imu_bag(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_imu(tmp_path_factory.mktemp("query") / "imu.bag")


def query(*args: str, code: int = 0) -> subprocess.CompletedProcess[str]:
    done = run_cli("bag", "query", *args)
    assert done.returncode == code, done.stderr
    assert "Traceback" not in done.stderr
    return done


def test_the_issues_example_as_csv_and_json(imu_bag: Path) -> None:
    expected = expected_per_second()
    rows = list(csv.reader(io.StringIO(query(EXAMPLE, str(imu_bag), "-F", "csv").stdout)))
    assert rows[0] == ["s", "avg(linear_acceleration.z)"]
    assert {s: float(z) for s, z in rows[1:]} == pytest.approx(expected)
    lines = query(EXAMPLE + " ORDER BY s", str(imu_bag), "--format", "json").stdout
    objects = [json.loads(line) for line in lines.splitlines()]
    assert [o["s"] for o in objects] == sorted(expected)
    assert [o["avg(linear_acceleration.z)"] for o in objects] == pytest.approx(
        [expected[s] for s in sorted(expected)]
    )


def test_a_table_on_the_terminal_and_the_row_count(imu_bag: Path) -> None:
    """The default is a table: the names as headers, DuckDB's text of each value."""
    done = query(
        'SELECT header.seq AS seq, header.frame_id AS frame, header.stamp FROM "/imu" '
        "ORDER BY seq LIMIT 2",
        str(imu_bag),
    )
    head, *body = [line for line in done.stdout.splitlines() if "│" in line or "┃" in line]
    assert head.split("┃")[1:4] == [" seq ", " frame    ", " stamp                         "]
    first = datetime.fromtimestamp(START_S, timezone.utc).strftime("%Y-%m-%d %H:%M:%S")
    assert [c.strip() for c in body[0].split("│")[1:4]] == ["0", "imu_link", first]
    assert [c.strip() for c in body[1].split("│")[1:4]] == ["1", "imu_link", f"{first}.333333333"]
    assert done.stderr == "(2 rows)\n"


def test_topics_join_and_a_window(imu_bag: Path) -> None:
    """Two topics in one statement; --start/--end count from the bag's start, as every bag
    command's; -t leaves out the views of other topics."""
    sql = (
        'SELECT count(*), sum(c.data), max(i.linear_acceleration.y) FROM "/imu" i '
        'JOIN "/count" c ON c.record_time - i.record_time = INTERVAL 1 millisecond'
    )
    assert query(sql, str(imu_bag), "-F", "csv").stdout.splitlines()[1] == "12,66,11.0"
    # the bag starts at message 0's record time; 1.0 s later is message 3's stamp + 1 ms
    window = query(sql, str(imu_bag), "-F", "csv", "--start", "0.9", "--end", "1.9")
    assert window.stdout.splitlines()[1] == f"3,{3 + 4 + 5},5.0"
    only = query('SELECT * FROM "/count"', str(imu_bag), "-t", "/imu", code=3)
    assert only.stderr.startswith('rostools: no topic /count in the bags: they hold "/imu"')


def test_sql_errors_are_one_line_and_exit_2(imu_bag: Path) -> None:
    bad = query("SELEC 1", str(imu_bag), code=2)
    assert bad.stderr == 'rostools: Parser Error: syntax error at or near "SELEC"\n'
    column = query('SELECT nope FROM "/imu"', str(imu_bag), code=2)
    assert column.stderr.startswith('rostools: Binder Error: Referenced column "nope" not found')
    assert len(column.stderr.splitlines()) == 1
    runtime = query("SELECT CAST('x' AS INTEGER)", str(imu_bag), code=2)
    assert runtime.stderr.startswith("rostools: Conversion Error:"), runtime.stderr


def test_a_topic_not_in_the_bags_names_those_there(imu_bag: Path) -> None:
    done = query('SELECT count(*) FROM "/odom"', str(imu_bag), code=3)
    assert done.stderr == 'rostools: no topic /odom in the bags: they hold "/count", "/imu"\n'
    bare = query("SELECT count(*) FROM imu", str(imu_bag), code=3)
    assert bare.stderr == (
        'rostools: no topic imu in the bags: they hold "/count", "/imu"'
        ' (hint: a topic is a quoted name: SELECT * FROM "/imu")\n'
    )


def test_a_damaged_bag_is_data_loss_in_one_line(tmp_path: Path) -> None:
    """A bag cut short: the error the reader raised while DuckDB scanned, exit 6, not DuckDB's
    wrapping of it."""
    whole = write_sample(tmp_path / "whole.bag", 400, chunk_size=2048).path.read_bytes()
    cut = tmp_path / "cut.bag"
    cut.write_bytes(whole[: len(whole) * 2 // 3])
    done = query('SELECT count(*) FROM "/count"', str(cut), code=6)
    assert done.stderr.startswith("rostools: read "), done.stderr
    assert "messages of /count, but left out what could not be read" in done.stderr
    assert len(done.stderr.splitlines()) == 1


def test_without_duckdb_one_line_names_the_extra(imu_bag: Path) -> None:
    code = (
        "import sys\nsys.modules['duckdb'] = None\n"  # import duckdb fails, as uninstalled
        "from rostools.cli import main\n"
        f"main(['bag', 'query', 'SELECT 1', {str(imu_bag)!r}])"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert done.returncode == 2
    assert done.stderr == ("rostools: bag query needs duckdb: pip install 'rostools[sql]'\n")


def test_only_the_topics_a_query_reads_are_decoded(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Every topic is a view, but a stream is opened only for a topic a query scans, once
    per scan: a self-join reads it twice, and nothing else is read."""
    from rostools.bag.tables import batches
    from rostools.bag.tables.sql import connect

    sample = write_sample(tmp_path / "s.bag", 40)
    opened: list[str] = []
    real = batches.topic_batches

    def counting(paths, topic, **kwargs):  # type: ignore[no-untyped-def]
        opened.append(topic)
        return real(paths, topic, **kwargs)

    monkeypatch.setattr(batches, "topic_batches", counting)
    db = connect([sample.path])
    try:
        assert sorted(db.sources) == ["/chatter", "/count", "/point"]
        assert db.table('SELECT count(*) AS n FROM "/count"').to_pylist() == [{"n": 10}]
        assert opened == ["/count"]
        joined = db.table('SELECT count(*) AS n FROM "/point" a JOIN "/point" b USING (x)')
        assert joined.to_pylist() == [{"n": 10}]
        assert opened == ["/count", "/point", "/point"]
    finally:
        db.close()


@needs_corpus
def test_a_corpus_bag_agrees_with_pyarrow_compute() -> None:
    """rosbag.js's turtlesim bag: counts, sums and extremes as pyarrow.compute finds them
    on topic_batches, and a nested array (tf's transforms) unnested."""
    import pyarrow.compute as pc

    from rostools.bag.tables.batches import topic_batches

    bag = CORPUS / "ros1" / "rosbag.js" / "example.bag"
    pose = topic_batches([bag], "/turtle1/pose").read_all()
    done = query(
        'SELECT count(*), sum(x), min(theta), max(linear_velocity) FROM "/turtle1/pose"',
        str(bag), "-F", "json",
    )  # fmt: skip
    row = json.loads(done.stdout)
    assert row["count_star()"] == pose.num_rows
    assert row["sum(x)"] == pytest.approx(pc.sum(pose["x"]).as_py())
    assert row["min(theta)"] == pc.min(pose["theta"]).as_py()
    assert row["max(linear_velocity)"] == pc.max(pose["linear_velocity"]).as_py()
    tf = topic_batches([bag], "/tf").read_all()
    frames = query(
        'SELECT t.child_frame_id AS child, count(*) AS n FROM (SELECT unnest(transforms) AS t '
        'FROM "/tf") GROUP BY child ORDER BY child',
        str(bag), "-F", "csv",
    )  # fmt: skip
    counted: dict[str, int] = defaultdict(int)
    for transforms in tf["transforms"].to_pylist():
        for t in transforms:
            counted[t["child_frame_id"]] += 1
    assert frames.stdout.splitlines() == ["child,n"] + [
        f"{k},{v}" for k, v in sorted(counted.items())
    ]


def test_the_api_runs_the_same_engine(imu_bag: Path) -> None:
    """rostools.bag_sql: the command's answer as a pyarrow.Table, its errors rostools'."""
    import rostools

    table = rostools.bag_sql(EXAMPLE + " ORDER BY s", imu_bag)
    assert isinstance(table, pa.Table)
    expected = expected_per_second()
    assert table.column(1).to_pylist() == pytest.approx([expected[s] for s in sorted(expected)])
    with pytest.raises(
        rostools.NotFoundError, match='no topic /odom in the bags: they hold "/count"'
    ):
        rostools.bag_sql('SELECT * FROM "/odom"', [imu_bag])
    with pytest.raises(rostools.UsageError, match=r"^Conversion Error"):
        rostools.bag_sql("SELECT CAST('x' AS INTEGER)", imu_bag)  # raised as it runs


def test_the_streaming_reader_feeds_duckdb_pandas_and_polars(imu_bag: Path) -> None:
    """bag_batches' RecordBatchReader goes to DuckDB as it is (a replacement scan of a
    Python variable); its table to pandas and Polars without copying a float column."""
    import rostools

    reader = rostools.bag_batches(imu_bag, "/imu", batch_rows=5)
    assert isinstance(reader, pa.RecordBatchReader)
    counted = duckdb.sql("SELECT count(*), max(linear_acceleration.z) FROM reader").fetchall()
    assert counted == [(IMU_COUNT, (IMU_COUNT - 1) / 4)]
    flat = rostools.bag_table(imu_bag, "/imu", flatten=True).combine_chunks()
    z = flat.column("linear_acceleration.z")
    series = z.chunk(0).to_pandas(zero_copy_only=True)  # a pandas.Series on Arrow's buffer
    assert series.tolist() == [i / 4 for i in range(IMU_COUNT)]
    address = z.chunk(0).buffers()[1].address
    assert series.to_numpy().__array_interface__["data"][0] == address
    assert flat.to_pandas()["header.frame_id"].tolist() == ["imu_link"] * IMU_COUNT
    pl = pytest.importorskip("polars", reason="the test extra installs polars")
    column = pl.from_arrow(flat)["linear_acceleration.z"]  # type: ignore[index]
    assert column.to_list() == [i / 4 for i in range(IMU_COUNT)]


@needs_corpus
def test_a_topic_of_a_type_the_bag_does_not_define_says_why() -> None:
    """webviz's bag leaves its one type's definition out: no view, and a query that names it
    gets the reason, not DuckDB's "does not exist"."""
    bag = CORPUS / "ros1" / "webviz" / "bag-with-empty-message-definition.bag"
    done = query('SELECT count(*) FROM "/led_array_status"', str(bag), code=3)
    assert done.stderr == (
        "rostools: /led_array_status: unknown message type led_array_msgs/Status;"
        " the bag does not define it (ROSTOOLS_MSG_PATH can)\n"
    )


def test_json_rows_whatever_the_columns_are_named(imu_bag: Path) -> None:
    """A column named as the relation that to_json reads (it was "q") is still a column."""
    done = query('SELECT 1 AS q, 2 AS "row", 3 AS row_', str(imu_bag), "-F", "json")
    assert json.loads(done.stdout) == {"q": 1, "row": 2, "row_": 3}


def test_a_table_shows_its_first_rows_and_counts_the_rest(imu_bag: Path) -> None:
    from rostools.cli.bag.query import MAX_TABLE_ROWS

    done = query(f"SELECT range AS i FROM range({MAX_TABLE_ROWS + 5})", str(imu_bag))
    cells = [line.strip("│ ") for line in done.stdout.splitlines() if line.startswith("│")]
    assert cells == [str(i) for i in range(MAX_TABLE_ROWS)]
    assert done.stderr == (
        f"({MAX_TABLE_ROWS + 5} rows, 5 not shown: --format csv or json prints every row)\n"
    )
    every = query(f"SELECT range FROM range({MAX_TABLE_ROWS + 5})", str(imu_bag), "-F", "csv")
    assert every.stdout.splitlines()[1:] == [str(i) for i in range(MAX_TABLE_ROWS + 5)]
