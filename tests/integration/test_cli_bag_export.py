"""``bag export`` (issue 38): bags into a hive-partitioned dataset that other engines read.

The files are read back by pyarrow.dataset, DuckDB and Polars and compared, value by value,
with what ``topic_batches`` gives for each bag (the core's own tests compare that with genpy).
"""

from __future__ import annotations

import base64
import json
import math
import struct
from pathlib import Path
from typing import Any

import pytest

from rostools.bag.formats.access import open_writer
from rostools.msgs.codec import Codec
from rostools.msgs.store import TypeStore
from tests.support.bagdata import INT32_MD5, STRING_MD5
from tests.support.env import CORPUS, needs_corpus, run_cli

pa = pytest.importorskip(
    "pyarrow", reason="bag export needs pyarrow: pip install 'rostools[arrow]'"
)
duckdb = pytest.importorskip("duckdb", reason="pip install 'rostools[sql]'")

SAMPLE = "test_msgs/Sample"
SAMPLE_DEF = """std_msgs/Header header
float64 value
uint8[] blob
geometry_msgs/Point[] points
string name
duration d
int32[3] fixed
================================================================================
MSG: std_msgs/Header
uint32 seq
time stamp
string frame_id
================================================================================
MSG: geometry_msgs/Point
float64 x
float64 y
float64 z
"""
STORE = TypeStore.default().with_definition(SAMPLE, SAMPLE_DEF)
CODEC = Codec.of(STORE)


def _sample(i: int, base_s: int) -> bytes:
    """Message ``i``: a NaN now and then, empty arrays, bytes that are not text."""
    cls = CODEC.message_class(SAMPLE)
    point = CODEC.message_class("geometry_msgs/Point")
    msg = cls()
    msg.header.seq = i
    msg.header.stamp.secs, msg.header.stamp.nsecs = base_s + i, 7 * i
    msg.header.frame_id = f"f{i}"
    msg.value = math.nan if i % 5 == 0 else i / 3
    msg.blob = bytes([255, 0, i % 256][: i % 4])
    msg.points = [point(x=k, y=-k, z=i) for k in range(i % 3)]
    msg.name = "ü" * (i % 2)
    msg.d.secs, msg.d.nsecs = -i, 5
    msg.fixed = [i, -i, 2**31 - 1]
    return CODEC.serialize(msg)


def write_bag(path: Path, count: int, base_s: int, *, count_type: str = "int32") -> Path:
    """``/sample`` (nested, arrays, NaN) and ``/count`` (Int32, or String) interleaved."""
    with open_writer(path) as writer:
        sample = writer.add_connection("/sample", SAMPLE, STORE.md5(SAMPLE), SAMPLE_DEF,
                                       callerid="/a")  # fmt: skip
        if count_type == "int32":
            counter = writer.add_connection("/count", "std_msgs/Int32", INT32_MD5, "int32 data\n")
        else:
            counter = writer.add_connection("/count", "std_msgs/String", STRING_MD5,
                                            "string data\n")  # fmt: skip
        for i in range(count):
            t = base_s * 10**9 + i * 10_000_000
            writer.write(sample, t, _sample(i, base_s))
            data = struct.pack("<i", i) if count_type == "int32" else struct.pack("<I", 1) + b"s"
            writer.write(counter, t + 1, data)
    return path


def plain(value: Any) -> Any:
    """Rows as comparable plain data: NaN as a string (NaN != NaN), tuples as lists."""
    if isinstance(value, float) and math.isnan(value):
        return "NaN"
    if isinstance(value, dict):
        return {k: plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [plain(v) for v in value]
    return value


def _int_times(kind: Any) -> Any:
    if pa.types.is_timestamp(kind) or pa.types.is_duration(kind):
        return pa.int64()
    if pa.types.is_struct(kind):
        return pa.struct([f.with_type(_int_times(f.type)) for f in kind])
    if pa.types.is_fixed_size_list(kind):
        return pa.list_(_int_times(kind.value_type), kind.list_size)
    if pa.types.is_list(kind) or pa.types.is_large_list(kind):
        return pa.list_(_int_times(kind.value_type))
    if pa.types.is_large_string(kind):
        return pa.string()
    if pa.types.is_large_binary(kind):
        return pa.binary()
    return kind


def rows(table: Any, drop: tuple[str, ...] = ("bag", "topic")) -> list[Any]:
    """A table's rows, its times as int ns (to_pylist keeps only us), in record time order."""
    table = table.drop_columns([c for c in drop if c in table.column_names])
    table = table.cast(pa.schema([f.with_type(_int_times(f.type)) for f in table.schema]))
    return plain(sorted(table.to_pylist(), key=lambda r: r["record_time"]))


def expected(bag: Path, topic: str, *, flatten: bool = False, md5sum: str | None = None) -> Any:
    """What ``topic_batches`` gives for one bag, with the two columns the export adds."""
    from rostools.bag.formats.access import bag_info
    from rostools.bag.tables.batches import topic_batches

    table = topic_batches([bag], topic, flatten=flatten, md5sum=md5sum).read_all()
    n, kind = table.num_rows, table.schema.field("record_time").type
    table = table.append_column("bag_name", pa.array([bag.name] * n))
    start = bag_info(bag).start_ns
    return table.append_column("bag_start", pa.array([start] * n, kind))


@pytest.fixture(scope="module")
def two_bags(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path]:
    folder = tmp_path_factory.mktemp("bags")
    return write_bag(folder / "run-a.bag", 120, 1_700_000_000), write_bag(
        folder / "run-b.mcap", 80, 1_700_000_100
    )


def test_parquet_dataset_reads_back_in_pyarrow_duckdb_and_polars(
    tmp_path: Path, two_bags: tuple[Path, Path]
) -> None:
    import pyarrow.dataset as ds

    out = tmp_path / "out"
    done = run_cli("--format", "json", "bag", "export", *map(str, two_bags), "-o", str(out),
                   "-j", "2")  # fmt: skip
    assert done.returncode == 0, done.stderr
    *progress, report = map(json.loads, done.stdout.splitlines())
    assert report["rows"] == 400 and report["files"] == 4 and report["split"] == []
    # the rows the two processes wrote, counted back as they went
    assert progress and progress[-1] == {"progress": "export", "done": 400, "total": 400}
    assert [p["done"] for p in progress] == sorted(p["done"] for p in progress)
    assert {t["path"] for t in report["tables"]} == {"topic=sample", "topic=count"}
    assert {f for t in report["tables"] for f in t["files"]} == {
        f"topic={t}/bag={b}/part-0.parquet" for t in ("sample", "count") for b in ("run-a", "run-b")
    }
    for topic in ("/sample", "/count"):
        key = topic[1:]
        folder = out / f"topic={key}"
        dataset = ds.dataset(folder, format="parquet", partitioning="hive").to_table()
        sql = duckdb.sql(
            f"SELECT * FROM read_parquet('{folder}/**/*.parquet', hive_partitioning = true)"
        ).arrow()
        sql = sql.read_all() if hasattr(sql, "read_all") else sql
        for bag in two_bags:
            want = rows(expected(bag, topic))
            stem = bag.stem
            got = dataset.filter(ds.field("bag") == stem)
            assert rows(got) == want
            theirs = sql.filter(pa.compute.equal(sql["bag"], stem))
            assert rows(theirs) == want
        # one glob over the whole dataset: topic and bag are columns, bag_name the file's name
        counts = duckdb.sql(
            f"SELECT topic, bag, bag_name, count(*) FROM read_parquet('{out}/**/*.parquet', "
            "hive_partitioning = true, union_by_name = true) GROUP BY ALL ORDER BY ALL"
        ).fetchall()
    assert counts == [
        ("count", "run-a", "run-a.bag", 120), ("count", "run-b", "run-b.mcap", 80),
        ("sample", "run-a", "run-a.bag", 120), ("sample", "run-b", "run-b.mcap", 80),
    ]  # fmt: skip
    polars = pytest.importorskip("polars", reason="pip install polars (the test extra has it)")
    frame = polars.scan_parquet(f"{out}/topic=sample/**/*.parquet", hive_partitioning=True)
    got = frame.filter(polars.col("bag") == "run-b").collect().to_arrow()
    assert rows(got) == rows(expected(two_bags[1], "/sample"))


def test_a_topic_whose_definition_changes_is_one_table_per_md5sum(tmp_path: Path) -> None:
    a = write_bag(tmp_path / "a.bag", 5, 100)
    b = write_bag(tmp_path / "b.bag", 4, 200, count_type="string")
    out = tmp_path / "out"
    done = run_cli("--format", "json", "bag", "export", str(a), str(b), "-o", str(out), "-j", "1",
                   "-t", "/count")  # fmt: skip
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout.splitlines()[-1])
    keys = {INT32_MD5: f"count@{INT32_MD5[:8]}", STRING_MD5: f"count@{STRING_MD5[:8]}"}
    assert report["split"] == [{"topic": "/count", "tables": [
        {"md5sum": m, "path": f"topic={keys[m]}"} for m in sorted(keys)]}]  # fmt: skip
    import pyarrow.dataset as ds

    for bag, md5 in ((a, INT32_MD5), (b, STRING_MD5)):
        table = ds.dataset(out / f"topic={keys[md5]}", partitioning="hive").to_table()
        assert rows(table) == rows(expected(bag, "/count", md5sum=md5))
    text = run_cli("bag", "export", str(a), str(b), "-o", str(out), "--force", "-t", "/count")
    assert text.returncode == 0, text.stderr
    assert f"note: /count changes definition between the bags: one table for each md5sum, " \
           f"topic={keys[STRING_MD5]} ({STRING_MD5}), topic={keys[INT32_MD5]} ({INT32_MD5})" \
           in text.stderr  # fmt: skip


def test_arrow_csv_and_ndjson_read_back(tmp_path: Path, two_bags: tuple[Path, Path]) -> None:
    import pyarrow.csv as pcsv
    import pyarrow.dataset as ds

    bag = two_bags[0]
    for fmt in ("arrow", "csv", "ndjson"):
        out = tmp_path / fmt
        done = run_cli("bag", "export", str(bag), "-o", str(out), "--format", fmt, "-t", "/sample")
        assert done.returncode == 0, done.stderr
    # Arrow IPC files: the schema whole, as Parquet's
    ipc = ds.dataset(tmp_path / "arrow", format="ipc", partitioning="hive").to_table()
    assert rows(ipc) == rows(expected(bag, "/sample"))
    # CSV: flattened (implied), arrays as JSON text, bytes as base64, times ISO 8601 in ns
    want = expected(bag, "/sample", flatten=True)
    only_empty = pcsv.ConvertOptions(null_values=[""])  # "nan" is NaN, not pyarrow's null
    table = pcsv.read_csv(out.parent / "csv/topic=sample/bag=run-a/part-0.csv",
                          convert_options=only_empty)  # fmt: skip
    assert table.column_names == want.column_names
    assert table.num_rows == want.num_rows == 120
    for name in ("header.seq", "header.frame_id", "value", "bag_name"):
        assert plain(table[name].to_pylist()) == plain(want[name].to_pylist()), name
    assert table["header.stamp"].cast(pa.int64()).to_pylist() == want["header.stamp"].cast(
        pa.int64()).to_pylist()  # fmt: skip
    blobs = [base64.b64decode(v or "") for v in table["blob"].to_pylist()]
    assert blobs == want["blob"].to_pylist()
    assert [json.loads(v) for v in table["points"].to_pylist()] == want["points"].to_pylist()
    assert [json.loads(v) for v in table["fixed"].to_pylist()] == want["fixed"].to_pylist()
    assert table["d"].to_pylist() == want["d"].cast(pa.int64()).to_pylist()
    # NDJSON: nested objects, times and durations as int ns, NaN as "nan", bytes as base64
    lines = (tmp_path / "ndjson/topic=sample/bag=run-a/part-0.ndjson").read_text().splitlines()
    nested = rows(expected(bag, "/sample"))
    got = [json.loads(line) for line in lines]
    for row in got:
        row["blob"] = list(base64.b64decode(row["blob"]))
        row["value"] = "NaN" if row["value"] == "nan" else row["value"]
    for row in nested:
        row["blob"] = list(row["blob"])
    assert got == nested


def test_start_and_end_cut_at_the_exact_nanosecond(
    tmp_path: Path, two_bags: tuple[Path, Path]
) -> None:
    """As bag filter's: a message recorded exactly at --start or --end is in (seconds as a
    float, at 1.7e9 s, are hundreds of ns coarse)."""
    bag = two_bags[0]  # /sample every 10 ms from 1,700,000,000 s, /count 1 ns after each
    out = tmp_path / "out"
    done = run_cli("--format", "json", "bag", "export", str(bag), "-o", str(out),
                   "--start", "0.03", "--end", "0.05")  # fmt: skip
    assert done.returncode == 0, done.stderr
    report = json.loads(done.stdout.splitlines()[-1])
    assert {t["topic"]: t["rows"] for t in report["tables"]} == {"/sample": 3, "/count": 2}
    filtered = tmp_path / "f.bag"
    assert run_cli("bag", "filter", str(bag), str(filtered), "--start", "0.03", "--end", "0.05",
                   "-q").returncode == 0  # fmt: skip
    from rostools.bag.formats.access import bag_info

    assert bag_info(filtered).message_count == 5


def test_bad_input_is_one_line_and_its_exit_code(
    tmp_path: Path, two_bags: tuple[Path, Path]
) -> None:
    bag = str(two_bags[0])
    out = tmp_path / "out"
    cases = [
        (["nope.bag"], 3, "no such bag: nope.bag"),
        ([bag, "-t", "/nothing"], 3, "no bag holds /nothing"),
        ([bag, bag], 2, "two bags would share bag=run-a"),
        ([bag, "--format", "xlsx"], 2, "xlsx"),
    ]
    for args, code, line in cases:
        done = run_cli("bag", "export", *args, "-o", str(out))
        assert done.returncode == code, (args, done.stderr)
        assert line in done.stderr and "Traceback" not in done.stderr, done.stderr
        assert not out.exists()
    not_a_bag = tmp_path / "x.bag"
    not_a_bag.write_text("hello")
    done = run_cli("bag", "export", str(not_a_bag), "-o", str(out))
    assert done.returncode == 1 and len(done.stderr.splitlines()) == 1, done.stderr
    # an existing output: refused, replaced with --force, never when it holds other files
    assert run_cli("bag", "export", bag, "-o", str(out), "-t", "/count").returncode == 0
    again = run_cli("bag", "export", bag, "-o", str(out))
    assert again.returncode == 2 and "exists; refusing to overwrite it" in again.stderr
    assert run_cli("bag", "export", bag, "-o", str(out), "--force").returncode == 0
    assert {p.name for p in out.iterdir()} == {"topic=count", "topic=sample"}
    (out / "notes.txt").write_text("mine")
    refused = run_cli("bag", "export", bag, "-o", str(out), "--force")
    assert refused.returncode == 2 and "refusing to replace it" in refused.stderr
    assert (out / "notes.txt").read_text() == "mine"


def test_a_table_that_cannot_be_read_is_left_out_and_the_rest_written(tmp_path: Path) -> None:
    bag = tmp_path / "a.bag"
    with open_writer(bag) as writer:  # a type the bag does not define, sorted first
        unknown = writer.add_connection("/a_unknown", "nowhere_msgs/Thing", "0" * 32, "")
        count = writer.add_connection("/count", "std_msgs/Int32", INT32_MD5, "int32 data\n")
        writer.write(unknown, 1, b"\x01")
        writer.write(count, 2, struct.pack("<i", 7))
    out = tmp_path / "out"
    done = run_cli("bag", "export", str(bag), "-o", str(out), "-j", "1")
    assert done.returncode == 3, done.stderr
    assert done.stderr.splitlines()[-1].startswith(
        "rostools: left out 1 table that could not be read (the rest is written): /a_unknown: "
        "unknown message type nowhere_msgs/Thing"
    )
    assert [p.relative_to(out).as_posix() for p in out.rglob("*.parquet")] == [
        "topic=count/bag=a/part-0.parquet"
    ]


def test_without_pyarrow_the_line_names_the_extra(tmp_path: Path, cli_env: dict[str, str]) -> None:
    blocker = tmp_path / "block" / "pyarrow"
    blocker.mkdir(parents=True)
    (blocker / "__init__.py").write_text("raise ImportError('no pyarrow here')\n")
    bag = write_bag(tmp_path / "a.bag", 2, 100)
    env = {**cli_env, "PYTHONPATH": str(blocker.parent)}
    done = run_cli("bag", "export", str(bag), "-o", str(tmp_path / "out"), env=env)
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().splitlines() == [
        "rostools: bag export needs pyarrow: pip install 'rostools[arrow]'"
    ]
    assert not (tmp_path / "out").exists()


@needs_corpus
def test_a_damaged_corpus_bag_keeps_what_is_readable_and_exits_6(tmp_path: Path) -> None:
    cut = CORPUS / "ros1-derived" / "test1_cut_at_60pct.bag"
    out = tmp_path / "out"
    done = run_cli("--format", "json", "bag", "export", str(cut), "-o", str(out), "-t", "/imu/data")
    assert done.returncode == 6, done.stderr
    report = json.loads(done.stdout.splitlines()[-1])
    assert report["lost"] == [f"{cut}: chunk at 766584 is cut short (115869 of its bytes are "
                              "in the file); 0 messages salvaged from it"]  # fmt: skip
    assert done.stderr.count("\n") == 1 and "left out what could not be read" in done.stderr
    import pyarrow.dataset as ds

    table = ds.dataset(out / "topic=imu.data", partitioning="hive").to_table()
    assert table.num_rows == report["rows"] > 0


@needs_corpus
def test_a_corpus_bag_reads_back_as_topic_batches(tmp_path: Path) -> None:
    bag = CORPUS / "ros1" / "embag" / "array_test.bag"
    out = tmp_path / "out"
    done = run_cli("bag", "export", str(bag), "-o", str(out), "-q")
    assert done.returncode == 0, done.stderr
    import pyarrow.parquet as pq

    from rostools.bag.tables.batches import table_schemas

    tables = table_schemas([bag])
    assert tables
    for table in tables:
        folder = out / f"topic={table.topic[1:].replace('/', '.')}"
        got = pq.read_table(folder / "bag=array_test" / "part-0.parquet")
        assert rows(got) == rows(expected(bag, table.topic)), table.topic


def test_the_same_export_runs_on_a_dask_cluster(
    tmp_path: Path, two_bags: tuple[Path, Path]
) -> None:
    """``export_bag`` on Dask's distributed scheduler, as docs/tables.md shows it."""
    distributed = pytest.importorskip(
        "dask.distributed", reason="pip install 'dask[distributed]' (the test extra has it)"
    )
    from rostools.bag.tables.dataset import export_bag
    from rostools.bag.tables.export import plan_export, prepare_output

    out = tmp_path / "out"
    plan = plan_export(list(two_bags), out)
    prepare_output(out, overwrite=False)
    with (
        distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                 host="127.0.0.1", dashboard_address="127.0.0.1:0") as cluster,
        distributed.Client(cluster) as client,
    ):  # fmt: skip
        done = client.gather(client.map(export_bag, plan.tasks))
        workers = {p for p in client.run(lambda: __import__("os").getpid()).values()}
    assert len(workers) == 2
    assert [r.path for r in done] == [str(b) for b in two_bags] and not any(r.lost for r in done)
    import pyarrow.dataset as ds

    for topic in ("/sample", "/count"):
        table = ds.dataset(out / f"topic={topic[1:]}", partitioning="hive").to_table()
        for bag in two_bags:
            got = table.filter(ds.field("bag") == bag.stem)
            assert rows(got) == rows(expected(bag, topic))


@needs_corpus
def test_a_ros2_mcap_is_refused_before_anything_is_written(tmp_path: Path) -> None:
    talker = CORPUS / "mcap" / "rosbag2" / "rosbag2_py" / "talker" / "talker.mcap"
    out = tmp_path / "out"
    done = run_cli("bag", "export", str(talker), "-o", str(out))
    assert done.returncode == 1, done.stderr
    assert len(done.stderr.splitlines()) == 1, done.stderr
    assert "holds ROS 2 CDR messages" in done.stderr
    assert "bag export does not support ROS 2 CDR" in done.stderr
    assert not out.exists()
