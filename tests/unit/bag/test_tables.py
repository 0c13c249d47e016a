"""Bags as Arrow tables (bag/tables/): the schema of a type, batches, windows, flat names,
the choice of a definition, and bad input in one line. Values against genpy are in
tests/interop/test_tables_genpy.py and tests/corpus/test_tables_corpus.py."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import rostools
from rostools.bag.formats.access import open_writer
from rostools.bag.tables.batches import table_schemas, topic_batches
from rostools.bag.tables.columns import EMPTY_MEMBER
from rostools.errors import InvalidDataError, MissingExtraError, NotFoundError, UsageError
from rostools.msgs.codec import Codec
from rostools.msgs.store import TypeStore
from tests.support.bagdata import handmade_mcap
from tests.support.tables import EVERYTHING, plain_rows, synthetic_store, write_synthetic_bag

pa = pytest.importorskip("pyarrow", reason="the arrow extra (in the test extra)")

POINT = "float64 x\nfloat64 y\nfloat64 z\n"


@pytest.fixture(scope="module")
def synthetic(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return write_synthetic_bag(tmp_path_factory.mktemp("tables") / "every.bag")


def test_the_schema_follows_the_type_mapping(synthetic: Path) -> None:
    (every,) = [t for t in table_schemas([synthetic]) if t.topic == "/every"]
    assert (every.name, every.type, every.messages, every.error) == ("/every", EVERYTHING, 3, None)
    types = {f.name: f.type for f in every.schema}
    ns = pa.timestamp("ns")
    point = pa.struct([pa.field(c, pa.float64(), nullable=False) for c in "xyz"])
    inner = types["inner"]
    assert list(types)[:3] == ["record_time", "header", "b"]  # constants are not columns
    assert types["record_time"] == ns and types["header"].field("stamp").type == ns
    assert [types[n] for n in ("b", "i8", "u8", "by", "ch", "u64", "f32", "f64")] == [
        pa.bool_(), pa.int8(), pa.uint8(), pa.int8(), pa.uint8(), pa.uint64(), pa.float32(),
        pa.float64(),
    ]  # fmt: skip
    assert (types["s"], types["t"], types["d"]) == (pa.string(), ns, pa.duration("ns"))
    assert (types["blob"], types["chars"]) == (pa.binary(), pa.binary())
    assert (types["quad"], types["tri"]) == (pa.binary(4), pa.binary(3))
    assert types["floats"] == pa.list_(pa.float64())
    assert types["vec"] == pa.list_(pa.float32(), 3)
    assert types["names"] == pa.list_(pa.string()) and types["two_names"] == pa.list_(
        pa.string(), 2
    )
    assert types["times"] == pa.list_(ns) and types["durs"] == pa.list_(pa.duration("ns"), 2)
    assert [f.name for f in inner] == ["label", "points", "stamp", "data"]
    assert inner.field("points").type.value_type == point
    assert types["inners"].value_type == inner and types["fixed_inners"].list_size == 2
    assert types["points"].value_type == point and types["fixed_points"].list_size == 2
    # Parquet holds no struct of no fields, nor does DuckDB 1.x read one: ROS 2's one member
    assert types["nothing"] == pa.struct([pa.field(EMPTY_MEMBER, pa.uint8(), nullable=False)])
    (nothing,) = [t for t in table_schemas([synthetic]) if t.topic == "/nothing"]
    assert nothing.schema.names == ["record_time"]


def test_batches_stream_in_time_order_across_bags(tmp_path: Path) -> None:
    store = TypeStore.default()
    codec = Codec.of(store)
    point = codec.message_class("geometry_msgs/Point")
    for name, times in (("a.bag", (1, 4, 5)), ("b.mcap", (2, 3, 6))):
        with open_writer(tmp_path / name) as writer:
            conn = writer.add_connection(
                "/p", "geometry_msgs/Point", store.md5("geometry_msgs/Point"), POINT
            )
            for t in times:
                writer.write(conn, t * 1_000_000_000, codec.serialize(point(x=float(t))))
    paths = [tmp_path / "a.bag", tmp_path / "b.mcap"]
    reader = topic_batches(paths, "/p", batch_rows=4)
    sizes = [b.num_rows for b in reader]
    assert sizes == [4, 2]
    table = rostools.bag_table(paths, "/p", start=2, end=5)
    assert table.column("x").to_pylist() == [2.0, 3.0, 4.0, 5.0]
    assert table.column("record_time").cast(pa.int64()).to_pylist()[0] == 2_000_000_000
    flat = rostools.bag_batches(paths, "/p", flatten=True).read_all()
    assert flat.column_names == ["record_time", "x", "y", "z"]


def test_flatten_names_leaves_with_dots_and_keeps_lists(synthetic: Path) -> None:
    nested = rostools.bag_table(synthetic, "/every")
    flat = rostools.bag_table(synthetic, "/every", flatten=True)
    assert flat.column_names[:6] == [
        "record_time", "header.seq", "header.stamp", "header.frame_id", "b", "i8"
    ]  # fmt: skip
    assert "inner.points" in flat.column_names and "inners" in flat.column_names
    assert (
        flat.schema.field("inner.points").type
        == nested.schema.field("inner").type.field("points").type
    )
    assert flat.column("inner.label").to_pylist() == ["", "inside", ""]
    assert flat.column("header.seq").to_pylist() == [0, (1 << 32) - 1, 0]


def test_strings_that_are_not_utf8_read_with_replacement_characters(synthetic: Path) -> None:
    rows = plain_rows(rostools.bag_table(synthetic, "/every"))
    assert rows[1]["s"] == "caf\ufffd \ufffd\ufffd ok"
    assert rows[1]["names"] == ["", "ünïcode", "\ufffd("]
    assert rows[1]["inners"][1]["label"] == "\ufffd"


def test_arrays_of_time_keep_each_secs_with_its_nsecs(synthetic: Path) -> None:
    # the wire interleaves (secs, nsecs) per element: not all secs, then all nsecs
    rows = plain_rows(rostools.bag_table(synthetic, "/every"))
    assert rows[2]["times"] == [1_000_000_002, ((1 << 32) - 1) * 10**9]
    assert rows[2]["durs"] == [-1, 3 * 10**9]
    assert rows[1]["d"] == -(1 << 31) * 10**9 + 5


def test_duckdb_reads_header_stamp_from_the_nested_struct(synthetic: Path) -> None:
    duckdb = pytest.importorskip("duckdb", reason="the sql extra (in the test extra)")
    con = duckdb.connect()
    con.register("/every", rostools.bag_batches(synthetic, "/every"))
    found = con.sql(
        'SELECT epoch_ns(header.stamp) AS s, len(inners) AS n FROM "/every" ORDER BY record_time'
    ).fetchall()
    assert found == [(0, 0), (((1 << 32) - 1) * 10**9 + 999_999_999, 3), (1_700_000_000 * 10**9, 1)]


def test_a_nested_empty_message_goes_into_parquet(synthetic: Path, tmp_path: Path) -> None:
    # the defect: `bag export` of a type holding std_msgs/Empty-like fields was an internal
    # error ("Cannot write struct type 'nothing' with no child field to Parquet"), and a 0-byte
    # file left behind; DuckDB 1.5 (Python 3.10's) refused the same table
    import pyarrow.parquet as pq

    table = rostools.bag_table(synthetic, "/every")
    pq.write_table(table, tmp_path / "every.parquet")
    back = pq.read_table(tmp_path / "every.parquet")
    assert back.column("nothing").to_pylist() == [{EMPTY_MEMBER: 0}] * 3
    assert back.column("nothings").to_pylist() == table.column("nothings").to_pylist()


def _two_definitions(tmp_path: Path) -> list[Path]:
    paths = []
    for i, text in enumerate(("float64 x\n", "float64 x\nfloat64 y\n")):
        path = tmp_path / f"v{i}.bag"
        store = TypeStore([]).with_definition("demo/Moved", text)
        with open_writer(path) as writer:
            conn = writer.add_connection("/moved", "demo/Moved", store.md5("demo/Moved"), text)
            writer.write(conn, (i + 1) * 1_000_000_000, b"\x00" * 8 * (i + 1))
        paths.append(path)
    return paths


def test_a_topic_with_two_definitions_is_two_tables(tmp_path: Path) -> None:
    paths = _two_definitions(tmp_path)
    tables = table_schemas(paths)
    assert [(t.topic, t.messages, t.schema.names) for t in tables] == [
        ("/moved", 1, ["record_time", "x"]),
        ("/moved", 1, ["record_time", "x", "y"]),
    ]
    assert [t.name for t in tables] == [f"/moved@{t.md5sum[:8]}" for t in tables]
    with pytest.raises(UsageError, match=r"^/moved has 2 definitions in these bags \(md5sums"):
        topic_batches(paths, "/moved")
    second = topic_batches(paths, "/moved", md5sum=tables[1].md5sum).read_all()
    assert second.column_names == ["record_time", "x", "y"] and second.num_rows == 1


def test_bad_input_is_one_line(tmp_path: Path, synthetic: Path) -> None:
    with pytest.raises(NotFoundError, match=r"^topic /nope is not in .*every\.bag$"):
        topic_batches([synthetic], "/nope")
    with pytest.raises(UsageError, match="batch_rows must be at least 1"):
        topic_batches([synthetic], "/every", batch_rows=0)
    store = TypeStore.default()
    with open_writer(tmp_path / "short.bag") as writer:
        conn = writer.add_connection(
            "/p", "geometry_msgs/Point", store.md5("geometry_msgs/Point"), POINT
        )
        writer.write(conn, 1_000_000_000, b"\x00" * 24)
        writer.write(conn, 2_000_000_000, b"\x00" * 23)
    reader = topic_batches([tmp_path / "short.bag"], "/p", batch_rows=1)
    assert reader.read_next_batch().num_rows == 1  # what came before is handed over
    why = r"2\.000000000 is not a geometry_msgs/Point: message is shorter than its type says"
    with pytest.raises(InvalidDataError, match=rf"^/p: the message recorded at {why}$"):
        reader.read_next_batch()


def test_a_type_the_bag_does_not_define_is_named(tmp_path: Path) -> None:
    with open_writer(tmp_path / "blank.bag") as writer:
        conn = writer.add_connection("/x", "nowhere/Thing", "0" * 32, "")
        writer.write(conn, 1, b"\x01")
    (entry,) = table_schemas([tmp_path / "blank.bag"])
    assert entry.schema is None
    assert entry.error == (
        "/x: unknown message type nowhere/Thing; the bag does not define it (ROSTOOLS_MSG_PATH can)"
    )
    with pytest.raises(NotFoundError, match="unknown message type nowhere/Thing"):
        topic_batches([tmp_path / "blank.bag"], "/x")


def test_without_pyarrow_the_error_names_the_extra(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setitem(sys.modules, "pyarrow", None)  # import pyarrow raises ImportError
    with pytest.raises(MissingExtraError) as caught:
        rostools.bag_table("any.bag", "/x")
    assert str(caught.value) == "bag tables needs pyarrow: pip install 'rostools[arrow]'"
    assert caught.value.exit_code == 2


def test_the_api_loads_no_pyarrow_until_a_table_is_read() -> None:
    code = "import sys, rostools; rostools.bag_table; print('pyarrow' in sys.modules)"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "False"


def test_an_export_of_every_type_loads_no_pandas(synthetic: Path, tmp_path: Path) -> None:
    # pa.array and pa.scalar import pandas to inspect what they are given: half a second of
    # an export's start-up when pandas is installed.
    code = (
        "import sys; from pathlib import Path; from rostools.bag.tables.export import export;"
        f"export([Path({str(synthetic)!r})], Path({str(tmp_path / 'out')!r}), jobs=1);"
        "print('pandas' in sys.modules)"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "False"
    assert list((tmp_path / "out").rglob("*.parquet"))


def test_parquet_keeps_dictionaries_for_strings_only(synthetic: Path, tmp_path: Path) -> None:
    import pyarrow.parquet as pq

    from rostools.bag.tables.export import export

    export([synthetic], tmp_path / "out", jobs=1)
    parts = list((tmp_path / "out").rglob("*.parquet"))
    assert parts
    for part in parts:
        meta = pq.ParquetFile(part).metadata
        chunks = [meta.row_group(0).column(i) for i in range(meta.num_columns)]
        with_dictionary = {c.path_in_schema for c in chunks if c.dictionary_page_offset}
        strings = {c.path for c in map(meta.schema.column, range(meta.num_columns))
                   if c.logical_type.type == "STRING"}  # fmt: skip
        assert "bag_name" in strings
        assert with_dictionary == strings


def test_ros2_mcap_is_refused_in_one_line(tmp_path: Path) -> None:
    from rostools.bag.formats import mcap_format as fmt
    from rostools.bag.formats.model import UnsupportedBagError

    schema = fmt.encode_schema(1, "std_msgs/msg/String", "ros2msg", b"string data")
    path = handmade_mcap(
        tmp_path / "cdr.mcap", "ros2", schema + fmt.encode_channel(1, 1, "/x", "cdr", {})
    )
    with pytest.raises(UnsupportedBagError, match=r"^.*cdr\.mcap: /x holds ROS 2 CDR messages"):
        topic_batches([path], "/x")


def test_the_synthetic_store_is_what_the_bag_defines(synthetic: Path) -> None:
    # the bag's own definition is what the tables read: rostools' store has no tabletest types
    assert not TypeStore.default().has_msg(EVERYTHING)
    assert synthetic_store().has_msg(EVERYTHING)


def _odometry_bag(path: Path, frames: list[bytes]) -> list[Any]:
    store = TypeStore.default()
    codec = Codec.of(store)
    odom = codec.message_class("nav_msgs/Odometry")
    sent = []
    with open_writer(path) as writer:
        conn = writer.add_connection(
            "/odom", "nav_msgs/Odometry", store.md5("nav_msgs/Odometry"),
            store.full_text("nav_msgs/Odometry"),
        )  # fmt: skip
        for i, frame in enumerate(frames):
            msg = odom()
            msg.header.seq, msg.header.stamp.secs, msg.header.frame_id = i, i, frame
            msg.child_frame_id = "base_link"
            msg.pose.pose.position.x = i / 3
            msg.twist.covariance = [float(i)] * 36
            writer.write(conn, (i + 1) * 1_000_000_000, codec.serialize(msg))
            sent.append(msg)
    return sent


def test_a_batch_of_one_layout_reads_as_the_codec_decodes(tmp_path: Path) -> None:
    # batches of 3: one layout; a frame_id of another length; one that is not UTF-8
    frames = [b"odom"] * 3 + [b"odom", b"map", b"odom"] + [b"odom", b"o\xffom", b"odom"] + [b""] * 3
    sent = _odometry_bag(tmp_path / "odom.bag", frames)
    table = rostools.bag_table(tmp_path / "odom.bag", "/odom")
    by_batches = pa.Table.from_batches(
        list(topic_batches([tmp_path / "odom.bag"], "/odom", batch_rows=3))
    )
    assert by_batches.equals(table)
    rows = plain_rows(table)
    assert [r["header"]["frame_id"] for r in rows] == [f.decode("utf-8", "replace") for f in frames]
    assert [r["header"]["seq"] for r in rows] == list(range(12))
    assert [r["pose"]["pose"]["position"]["x"] for r in rows] == [
        m.pose.pose.position.x for m in sent
    ]
    assert [r["twist"]["covariance"] for r in rows] == [list(m.twist.covariance) for m in sent]
    assert {r["child_frame_id"] for r in rows} == {"base_link"}


def test_uniform_batches_are_read_in_one_go_and_others_are_not(tmp_path: Path) -> None:
    from rostools.bag.formats.access import open_bag
    from rostools.bag.formats.runs import Run
    from rostools.bag.tables.batches import _decoder
    from rostools.bag.tables.uniform import fill_uniform

    def runs(*batch: bytes) -> list[Run]:  # a batch as it comes: in runs, here one a message
        return [Run(np.zeros(1, np.int64), [memoryview(data)]) for data in batch]

    _odometry_bag(tmp_path / "odom.bag", [b"odom", b"odom", b"map", b"o\xffom"])
    with open_bag(tmp_path / "odom.bag") as reader:
        payloads = [bytes(d) for _, _, d in reader.messages()]
        decoder = _decoder(list(reader.connections))
    assert fill_uniform(decoder, runs(*payloads[:2]))
    decoder.clear()
    assert not fill_uniform(decoder, runs(*payloads[1:3]))  # two sizes
    assert not fill_uniform(decoder, runs(payloads[0], payloads[3]))  # same size, not UTF-8
    assert not fill_uniform(decoder, runs(payloads[0] + b"\x00", payloads[0] + b"\x00"))
    assert decoder.finish(0)[0].to_pylist() == []  # and nothing was filled by the refusals


def test_a_damaged_bag_gives_what_reads_then_says_what_it_lost(tmp_path: Path) -> None:
    from rostools.errors import DataLossError

    store = TypeStore.default()
    codec = Codec.of(store)
    point = codec.message_class("geometry_msgs/Point")
    path = tmp_path / "cut.mcap"
    with open_writer(path, compression="none", chunk_size=1000) as writer:
        conn = writer.add_connection(
            "/p", "geometry_msgs/Point", store.md5("geometry_msgs/Point"), POINT
        )
        for i in range(200):
            writer.write(conn, (i + 1) * 1_000_000, codec.serialize(point(x=float(i), y=1234.5)))
    raw = bytearray(path.read_bytes())
    middle = raw.index(codec.serialize(point(x=100.0, y=1234.5)))
    raw[middle + 20] ^= 0xFF  # in a chunk: its CRC no longer holds, so the chunk is left out
    path.write_bytes(bytes(raw))
    got: list[float] = []
    with pytest.raises(DataLossError, match=r"^read 1\d\d messages of /p, but left out") as caught:
        for batch in topic_batches([path], "/p", batch_rows=50):
            got += batch.column("x").to_pylist()
    assert caught.value.exit_code == 6
    assert 150 < len(got) < 200 and 100.0 not in got  # one chunk's messages, and only those
    assert got == sorted(set(got)) and got[:50] == [float(i) for i in range(50)]


def test_an_array_past_arrows_offsets_is_refused_not_wrapped() -> None:
    from rostools.bag.tables.columns import MAX_OFFSET, _offsets

    assert _offsets([MAX_OFFSET - 1, 1]).to_pylist() == [0, MAX_OFFSET - 1, MAX_OFFSET]
    with pytest.raises(InvalidDataError, match=r"^an array of 2147483648 elements is too long"):
        _offsets([MAX_OFFSET, 1])


def test_two_tables_of_one_type_read_at_once_keep_their_own_rows(tmp_path: Path) -> None:
    # DuckDB scans the views of a query on threads of its own: two topics of one type at once
    import threading

    store = TypeStore.default()
    codec = Codec.of(store)
    stamped = codec.message_class("geometry_msgs/PointStamped")
    path = tmp_path / "two.bag"
    with open_writer(path) as writer:
        conns = [
            writer.add_connection(
                topic,
                "geometry_msgs/PointStamped",
                store.md5("geometry_msgs/PointStamped"),
                store.full_text("geometry_msgs/PointStamped"),
            )
            for topic in ("/a", "/b")
        ]
        for i in range(3000):
            for sign, conn in zip((1.0, -1.0), conns, strict=True):
                msg = stamped()
                msg.point.x = sign * i
                msg.header.frame_id = "f" * (i % 3)  # layouts differ: message by message
                writer.write(conn, (i + 1) * 1_000_000, codec.serialize(msg))
    got: dict[str, list[float]] = {}

    def read(topic: str) -> None:
        try:
            reader = topic_batches([path], topic, batch_rows=5)
            got[topic] = [x for b in reader for x in b.column("point").field("x").to_pylist()]
        except Exception as err:  # noqa: BLE001 - the assertion below shows it
            got[topic] = [repr(err)]  # type: ignore[list-item]

    threads = [threading.Thread(target=read, args=(t,)) for t in ("/a", "/b")]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join()
    assert got["/a"] == [float(i) for i in range(3000)]
    assert got["/b"] == [-float(i) for i in range(3000)]


def test_batches_end_at_batch_rows_or_at_the_message_that_reaches_batch_bytes(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from rostools.bag.formats.runs import Run
    from rostools.bag.tables import batches

    monkeypatch.setattr(batches, "BATCH_BYTES", 100)
    sizes = [10] * 25 + [95, 3, 200, 1, 1, 1]
    data = [memoryview(bytes(n)) for n in sizes]
    runs = [Run(np.arange(a, b), data[a:b]) for a, b in ((0, 7), (7, 26), (26, 31))]
    cut = [[int(t) for part in parts for t in part.times] for parts in batches._cut(runs, 8)]
    # 8 rows three times; then 10 + 95 reaches 100, 3 + 200 passes it, and the rest
    assert cut == [
        list(range(0, 8)), list(range(8, 16)), list(range(16, 24)), [24, 25], [26, 27], [28, 29, 30]
    ]  # fmt: skip
