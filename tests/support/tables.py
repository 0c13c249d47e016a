"""Bags as tables in tests: a synthetic bag of types only it defines, Arrow rows as plain
values, and what real genpy decodes (``genpy_tables.py``, one system-python run for all bags).
"""

from __future__ import annotations

import math
import pickle
import subprocess
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

from rostools.bag.formats.access import open_writer
from rostools.bag.tables.batches import table_schemas, topic_batches
from rostools.msgs.codec import Codec
from rostools.msgs.store import BuiltinSource, Kind, Source, TypeStore
from tests.support.env import SYSTEM_PYTHON

#: The types of the synthetic bag, package ``tabletest``: rostools has never seen them.
TYPES = {
    "tabletest/Point": "float64 x\nfloat64 y\nfloat64 z\n",
    "tabletest/Nothing": "# no fields at all\nint32 ONLY_A_CONSTANT=7\n",
    "tabletest/Inner": "string label\nPoint[] points\ntime stamp\nuint8[] data\n",
    "tabletest/Everything": "\n".join(
        (
            "int8 CONST_I=-3",
            "string CONST_S=hello # not a comment",
            "Header header",
            "bool b",
            "int8 i8",
            "uint8 u8",
            "byte by",
            "char ch",
            "int16 i16",
            "uint16 u16",
            "int32 i32",
            "uint32 u32",
            "int64 i64",
            "uint64 u64",
            "float32 f32",
            "float64 f64",
            "string s",
            "time t",
            "duration d",
            "uint8[] blob",
            "char[] chars",
            "uint8[4] quad",
            "char[3] tri",
            "float64[] floats",
            "float32[3] vec",
            "int32[2] pair",
            "string[] names",
            "string[2] two_names",
            "time[] times",
            "duration[2] durs",
            "bool[] flags",
            "Inner inner",
            "Inner[] inners",
            "Inner[2] fixed_inners",
            "Point[] points",
            "Point[2] fixed_points",
            "Nothing nothing",
            "Nothing[] nothings",
            "",
        )
    ),
}
EVERYTHING = "tabletest/Everything"
U32_MAX = (1 << 32) - 1


class _Texts(Source):
    def text(self, kind: Kind, name: str) -> str | None:
        return TYPES.get(name) if kind == "msg" else None

    def packages(self, kind: Kind) -> Iterable[str]:
        return ["tabletest"] if kind == "msg" else []

    def types(self, kind: Kind, package: str) -> list[str]:
        return sorted(n.partition("/")[2] for n in TYPES) if kind == "msg" else []


def synthetic_store() -> TypeStore:
    """A store of ``TYPES`` and the built-in ones (for ``std_msgs/Header``)."""
    return TypeStore([_Texts(), BuiltinSource()])


def everything_messages(codec: Codec) -> list[Any]:
    """Messages of ``tabletest/Everything`` at the edges: zeros and empty arrays, the largest
    values, NaN and infinities, strings that are not UTF-8, nested arrays of messages."""
    cls = codec.message_class
    zero = cls(EVERYTHING)()
    big = cls(EVERYTHING)()
    big.header.seq = U32_MAX
    big.header.stamp.secs, big.header.stamp.nsecs = U32_MAX, 999_999_999
    big.header.frame_id = "map"
    big.b = True
    big.i8, big.u8, big.by, big.ch = -128, 255, 127, 255
    big.i16, big.u16, big.i32, big.u32 = -(1 << 15), (1 << 16) - 1, -(1 << 31), U32_MAX
    big.i64, big.u64 = -(1 << 63), (1 << 64) - 1
    big.f32, big.f64 = float("nan"), float("-inf")
    big.s = b"caf\xe9 \xff\xfe ok"  # Latin-1, not UTF-8
    big.t.secs, big.t.nsecs = U32_MAX, 999_999_999
    big.d.secs, big.d.nsecs = -(1 << 31), 5
    big.blob = bytes(range(256))
    big.chars = b"\x00abc\xff"
    big.quad = b"\x01\x02\x03\xff"
    big.tri = b"xyz"
    big.floats = [float("nan"), 1.5, -0.0, float("inf")]
    big.vec = [float("nan"), 3.25, -1e38]
    big.pair = [-(1 << 31), (1 << 31) - 1]
    big.names = ["", "ünïcode", b"\xc3\x28"]
    big.two_names = ["a", b"\x80"]
    big.times = []
    big.flags = [True, False, True]
    inner = cls("tabletest/Inner")
    point = cls("tabletest/Point")
    big.inner.label = "inside"
    big.inner.points = [point(x=1.0, y=2.0, z=float("nan"))]
    big.inner.data = b"\x00\x01"
    big.inner.stamp.secs = 7
    big.inners = [
        inner(label="first", points=[], data=b""),
        inner(label=b"\xff", points=[point(x=float(i)) for i in range(3)], data=b"\x09"),
        inner(),
    ]
    big.fixed_inners = [inner(label="f0"), inner(points=[point(z=-1.0)], data=b"x")]
    big.points = [point(x=float(i), y=-float(i), z=0.5) for i in range(5)]
    big.fixed_points = [point(x=1.0), point(y=float("nan"))]
    big.nothings = [cls("tabletest/Nothing")()] * 4
    some = cls(EVERYTHING)()
    some.header.stamp.secs = 1_700_000_000
    some.times = [type(some.t)(1, 2), type(some.t)(U32_MAX, 0)]
    some.durs = [type(some.d)(-1, 999_999_999), type(some.d)(3, 0)]
    some.inners = [inner(label="only", points=[point(y=2.0)])]
    return [zero, big, some]


def write_synthetic_bag(path: Path) -> Path:
    """A bag (``.bag`` or MCAP by the name) of three ``Everything`` messages on ``/every``,
    and ``/nothing`` of the empty type, defined only in the bag."""
    store = synthetic_store()
    codec = Codec.of(store)
    with open_writer(path, overwrite=True) as writer:
        every = writer.add_connection(
            "/every", EVERYTHING, store.md5(EVERYTHING), store.full_text(EVERYTHING), callerid="/t"
        )
        nothing = writer.add_connection(
            "/nothing",
            "tabletest/Nothing",
            store.md5("tabletest/Nothing"),
            store.full_text("tabletest/Nothing"),
        )
        for i, msg in enumerate(everything_messages(codec)):
            writer.write(every, 1_000_000_000 + i, codec.serialize(msg))
            writer.write(nothing, 1_000_000_000 + i, b"")
    return path


def genpy_view(paths: Sequence[Path]) -> dict[str, Any]:
    """What real genpy decodes from each bag, in one system-python run (``genpy_tables.py``)."""
    script = Path(__file__).parent / "genpy_tables.py"
    proc = subprocess.run(
        [SYSTEM_PYTHON, str(script), *map(str, paths)], capture_output=True, timeout=600, check=True
    )
    view: dict[str, Any] = pickle.loads(proc.stdout)  # our own script's output
    return view


def _ints(pa: Any, t: Any) -> Any:
    """The type with timestamps and durations as int64 (their nanoseconds), for plain rows."""
    if pa.types.is_timestamp(t) or pa.types.is_duration(t):
        return pa.int64()
    if pa.types.is_struct(t):
        return pa.struct([f.with_type(_ints(pa, f.type)) for f in t])
    if pa.types.is_fixed_size_list(t):
        return pa.list_(t.value_field.with_type(_ints(pa, t.value_type)), t.list_size)
    if pa.types.is_list(t):
        return pa.list_(t.value_field.with_type(_ints(pa, t.value_type)))
    return t


def plain_rows(table: Any) -> list[dict[str, Any]]:
    """Each row of a table as plain values: times as int ns, binary as bytes, lists as lists."""
    import pyarrow as pa

    schema = pa.schema([f.with_type(_ints(pa, f.type)) for f in table.schema])
    rows: list[dict[str, Any]] = table.cast(schema).to_pylist()
    return rows


def ours(
    paths: Sequence[Path], batch_rows: int = 1000
) -> dict[tuple[str, str], list[tuple[int, Any]]]:
    """Every table of the bags, as ``genpy_tables.py`` shapes genpy's: (time, fields)."""
    out = {}
    for entry in table_schemas(paths):
        reader = topic_batches(paths, entry.topic, md5sum=entry.md5sum, batch_rows=batch_rows)
        table = reader.read_all()
        assert table.schema == entry.schema
        rows = plain_rows(table)
        out[(entry.topic, entry.md5sum)] = [(r.pop("record_time"), r) for r in rows]
    return out


def same(a: Any, b: Any) -> bool:
    """Equal value by value, NaN equal to NaN, types strict (1 is not True, bytes not str)."""
    if isinstance(a, float) and isinstance(b, float):
        return (math.isnan(a) and math.isnan(b)) or (
            a == b and math.copysign(1, a) == math.copysign(1, b)
        )
    if isinstance(a, dict) and isinstance(b, dict):
        return list(a) == list(b) and all(same(a[k], b[k]) for k in a)
    if isinstance(a, list | tuple) and isinstance(b, list | tuple):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b, strict=True))
    return type(a) is type(b) and a == b


def first_difference(a: Any, b: Any, where: str = "") -> str | None:
    """Where two plain values first differ, for a failure that says which field."""
    if isinstance(a, dict) and isinstance(b, dict):
        if list(a) != list(b):
            return f"{where}: fields {list(a)} != {list(b)}"
        for k in a:
            found = first_difference(a[k], b[k], f"{where}.{k}")
            if found:
                return found
        return None
    if isinstance(a, list | tuple) and isinstance(b, list | tuple) and len(a) == len(b):
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            found = first_difference(x, y, f"{where}[{i}]")
            if found:
                return found
        return None
    return None if same(a, b) else f"{where}: {a!r} != {b!r}"
