"""Decoders generated per type that write a message's fields straight into columns.

As the codec (``msgs/codec.py``) does, each type gets the Python source of one function,
compiled once; here the function builds no message object. Each run of fixed-size fields
(through nested messages) is one slice of bytes appended to its run's list; a batch's slices
are joined and read by numpy in one go (a structured dtype), one column per field. Strings are
decoded into a list, ``uint8[]`` and ``char[]`` kept as bytes, variable arrays of primitives
kept as slices with their counts, and arrays of messages are a level of rows of their own
(their counts are the list offsets). An array of messages of fixed size is one slice for the
whole array. ``finish`` turns a batch into Arrow arrays, once per column; the columns' Arrow
types are the schema (``schema.py`` names the rules).
"""

from __future__ import annotations

import struct
from collections.abc import Sequence
from typing import Any

import numpy as np

from rostools.bag.tables.arrow import MAX_OFFSET, from_numpy, pyarrow, string_array
from rostools.errors import InvalidDataError
from rostools.msgs.codec import BYTE_TYPES, Codec, DecodeError
from rostools.msgs.codegen import GeneratedCode
from rostools.msgs.spec import Field, MsgSpec

#: numpy's code of each fixed-size primitive, little-endian as on the wire.
NUMPY_CODES = {
    "bool": "?", "int8": "<i1", "byte": "<i1", "uint8": "<u1", "char": "<u1",
    "int16": "<i2", "uint16": "<u2", "int32": "<i4", "uint32": "<u4",
    "int64": "<i8", "uint64": "<u8", "float32": "<f4", "float64": "<f8",
}  # fmt: skip
#: The two 32-bit halves of ``time`` (unsigned) and ``duration`` (signed).
TIME_CODES = {"time": "<u4", "duration": "<i4"}
_U32 = struct.Struct("<I")
_NS = 1_000_000_000


def _short() -> None:
    raise DecodeError("message is shorter than its type says")


def arrow_scalar(pa: Any, base: str) -> Any:
    """The Arrow type of one value of a builtin ROS type."""
    if base == "string":
        return pa.string()
    if base == "time":
        return pa.timestamp("ns")
    if base == "duration":
        return pa.duration("ns")
    if base == "bool":
        return pa.bool_()
    return pa.from_numpy_dtype(np.dtype(NUMPY_CODES[base]))


class Node:
    """One column being filled: its Arrow type, and the lists the generated code appends to."""

    type: Any

    def finish(self, rows: int) -> Any:
        """The Arrow array of this batch's ``rows`` values (the run tables are loaded)."""
        raise NotImplementedError

    def clear(self) -> None:
        """Forget this batch's values."""


class Run:
    """Consecutive fixed-size fields at one level of rows: one bytes slice per row."""

    def __init__(self, fields: list[tuple[str, str, tuple[int, ...]]]) -> None:
        self.dtype = np.dtype(fields)  # packed: numpy aligns nothing unless asked
        self.parts: list[Any] = []
        self.table: Any = None

    def load(self) -> None:
        """Read the batch's slices as one structured array."""
        self.table = np.frombuffer(b"".join(self.parts), self.dtype)

    def clear(self) -> None:
        """Forget the batch."""
        self.parts.clear()
        self.table = None


class RunColumn(Node):
    """A fixed-size field in a run: a primitive, ``time``, ``duration``, or a fixed array."""

    def __init__(self, pa: Any, key: str, base: str, length: int | None) -> None:
        self.run: Run | None = None  # set when the run it is in is closed
        self.key, self.base, self.length = key, base, length
        self.pa = pa
        scalar = arrow_scalar(pa, base)
        if length is None:
            self.type = scalar
        elif base in BYTE_TYPES:
            self.type = pa.binary(length)
        else:
            self.type = pa.list_(scalar, length)

    def finish(self, rows: int) -> Any:
        """Arrow values from the run's table."""
        pa = self.pa
        assert self.run is not None
        table = self.run.table
        if self.base in TIME_CODES:
            pairs = table[self.key]  # (secs, nsecs) last: the wire interleaves them
            ns = pairs[..., 0].astype(np.int64) * _NS + pairs[..., 1]
            values = from_numpy(
                pa, ns.reshape(-1), self.type if self.length is None else self.type.value_type
            )
        else:
            column = table[self.key]
            if self.length is not None and self.base in BYTE_TYPES:
                data = np.ascontiguousarray(column).tobytes()
                return pa.FixedSizeBinaryArray.from_buffers(
                    self.type, rows, [None, pa.py_buffer(data)]
                )
            values = from_numpy(pa, column.reshape(-1), arrow_scalar(pa, self.base))
        if self.length is None:
            return values
        return pa.FixedSizeListArray.from_arrays(values, self.length)


class StringColumn(Node):
    """``string``, or the elements of ``string[]``/``string[N]`` (``counts`` for the former)."""

    def __init__(self, pa: Any, is_array: bool, length: int | None) -> None:
        self.pa, self.length, self.is_array = pa, length, is_array
        self.values: list[str] = []
        self.counts: list[int] = []
        #: The batch's strings as one Arrow array, when ``uniform.py`` read them so.
        self.built: Any = None
        if not is_array:
            self.type = pa.string()
        else:
            self.type = pa.list_(pa.string(), length if length is not None else -1)

    def finish(self, rows: int) -> Any:
        """The strings, or lists of them."""
        if self.built is not None:
            return self.built
        values = string_array(self.pa, self.values)
        if not self.is_array:
            return values
        if self.length is not None:
            return self.pa.FixedSizeListArray.from_arrays(values, self.length)
        return self.pa.ListArray.from_arrays(_offsets(self.counts), values)

    def clear(self) -> None:
        """Forget the batch."""
        self.values.clear()
        self.counts.clear()
        self.built = None


class BytesColumn(Node):
    """``uint8[]``/``char[]``: Arrow binary, its bytes joined once per batch (one copy)."""

    def __init__(self, pa: Any) -> None:
        self.pa = pa
        self.type = pa.binary()
        self.counts: list[int] = []
        self.parts: list[Any] = []

    def finish(self, rows: int) -> Any:
        """The byte strings."""
        pa = self.pa
        data = pa.py_buffer(b"".join(self.parts))
        return pa.BinaryArray.from_buffers(
            self.type, rows, [None, _offsets(self.counts).buffers()[1], data]
        )

    def clear(self) -> None:
        """Forget the batch."""
        self.counts.clear()
        self.parts.clear()


class VarArrayColumn(Node):
    """A variable array of a fixed-size builtin: counts, and the elements' bytes."""

    def __init__(self, pa: Any, base: str) -> None:
        self.pa, self.base = pa, base
        self.type = pa.list_(arrow_scalar(pa, base))
        if base in TIME_CODES:
            self.dtype = np.dtype([("s", TIME_CODES[base]), ("n", TIME_CODES[base])])
        else:
            self.dtype = np.dtype(NUMPY_CODES[base])
        self.size = self.dtype.itemsize
        self.counts: list[int] = []
        self.parts: list[Any] = []

    def finish(self, rows: int) -> Any:
        """Lists of the elements."""
        raw = np.frombuffer(b"".join(self.parts), self.dtype)
        if self.base in TIME_CODES:
            raw = raw["s"].astype(np.int64) * _NS + raw["n"]
        values = from_numpy(self.pa, raw, self.type.value_type)
        return self.pa.ListArray.from_arrays(_offsets(self.counts), values)

    def clear(self) -> None:
        """Forget the batch."""
        self.counts.clear()
        self.parts.clear()


#: The one member of an empty message nested in another (``std_msgs/Empty``), always 0, as
#: ROS 2 defines every empty type: Parquet cannot store a struct of no fields, nor DuckDB 1.x
#: read one.
EMPTY_MEMBER = "structure_needs_at_least_one_member"


class StructColumn(Node):
    """A message: one column per field, at one level of rows."""

    def __init__(self, pa: Any, names: list[str], children: list[Node], nested: bool) -> None:
        self.pa, self.names, self.children = pa, names, children
        fields = [pa.field(n, c.type, nullable=False) for n, c in zip(names, children, strict=True)]
        self.placeholder = nested and not children
        if self.placeholder:
            fields = [pa.field(EMPTY_MEMBER, pa.uint8(), nullable=False)]
        self.type = pa.struct(fields)

    def arrays(self, rows: int) -> list[Any]:
        """One array per field."""
        return [c.finish(rows) for c in self.children]

    def finish(self, rows: int) -> Any:
        """The struct array."""
        if self.placeholder:
            zeros = from_numpy(self.pa, np.zeros(rows, np.uint8))
            return self.pa.StructArray.from_arrays([zeros], fields=list(self.type))
        if not self.children:  # the message itself is empty: rows of no fields
            return self.pa.array([{}] * rows, self.type)
        return self.pa.StructArray.from_arrays(self.arrays(rows), fields=list(self.type))


class MessageArrayColumn(Node):
    """An array of messages: a list of structs whose elements are a level of their own."""

    def __init__(self, pa: Any, element: StructColumn, length: int | None) -> None:
        self.pa, self.element, self.length = pa, element, length
        self.type = pa.list_(pa.field("item", element.type, nullable=False), length or -1)
        self.counts: list[int] = []

    def finish(self, rows: int) -> Any:
        """Lists of the elements."""
        if self.length is not None:
            values = self.element.finish(rows * self.length)
            return self.pa.FixedSizeListArray.from_arrays(values, type=self.type)
        offsets = _offsets(self.counts)
        values = self.element.finish(int(offsets[-1].as_py()))
        return self.pa.ListArray.from_arrays(offsets, values, type=self.type)

    def clear(self) -> None:
        """Forget the batch."""
        self.counts.clear()


def _offsets(counts: list[int]) -> Any:
    pa = pyarrow()
    offsets = np.zeros(len(counts) + 1, np.int64)
    np.cumsum(counts, out=offsets[1:])
    if offsets[-1] > MAX_OFFSET:  # one message of 2 GiB: refused, not wrapped around
        raise InvalidDataError(f"an array of {int(offsets[-1])} elements is too long for a table")
    return from_numpy(pa, offsets.astype(np.int32))


class ColumnDecoder:
    """The generated decoder of one type into columns, and its columns.

    ``fill(buf)`` appends one message's fields (raises on bytes that do not fit); ``finish(n)``
    gives the arrays of the ``n`` messages filled since the last ``clear``; ``fields`` are the
    top-level Arrow fields, in the message's order. One per stream: its columns are its own,
    so two streams of one type (two views DuckDB scans on two threads) never share them.
    """

    def __init__(self, codec: Codec, type_name: str) -> None:
        self.pa = pa = pyarrow()
        self.codec = codec
        self.type_name = type_name
        self.runs: list[Run] = []
        self.nodes: list[Node] = []
        gen = _Gen(self, pa)
        self.root = gen.message(codec.store.msg(type_name), "")
        gen.flush()
        gen.line(f"if pos > end: {gen.ref(_short, 'f')}()")
        self.fill = gen.compile("fill(buf)", "columns", type_name, bind=True)
        #: Runs and strings in wire order when that is all the type holds (``uniform.py``).
        self.ops = gen.ops
        self.fields = list(self.root.type)

    def finish(self, rows: int) -> list[Any]:
        """The top-level arrays of this batch; then the batch is cleared."""
        for run in self.runs:
            run.load()
        try:
            return self.root.arrays(rows)
        finally:
            self.clear()

    def clear(self) -> None:
        """Forget every value filled since the last batch."""
        for run in self.runs:
            run.clear()
        for node in self.nodes:
            node.clear()


class _Gen(GeneratedCode):
    """The source of one fill function: runs of fixed fields, then the others, in order."""

    def __init__(self, decoder: ColumnDecoder, pa: Any) -> None:
        super().__init__()
        self.decoder, self.pa = decoder, pa
        self.lines.append(self.indent + "pos = 0")
        self.lines.append(self.indent + "end = len(buf)")
        #: What the function reads, in order, while it is only runs and strings: (run, its
        #: size) or (string column, 0). None once it reads an array: no uniform batches then.
        self.ops: list[tuple[Run | StringColumn, int]] | None = []
        self.pending_columns: list[tuple[str, str, int | None]] = []
        self.waiting: dict[str, RunColumn] = {}  # the pending columns, by their key in the run
        self.size = 0  # bytes pending in the current run

    def node(self, node: Node) -> Node:
        self.decoder.nodes.append(node)
        return node

    def flush(self) -> None:
        """Close the current run: one slice per row."""
        if not self.pending_columns:
            return
        run = self._new_run()
        if self.ops is not None:
            self.ops.append((run, self.size))
        parts = self.ref(run.parts.append, "a")
        self.line(f"{parts}(buf[pos:pos + {self.size}])")
        self.line(f"pos += {self.size}")
        self.size = 0

    def _new_run(self) -> Run:
        fields: list[tuple[str, str, tuple[int, ...]]] = []
        for key, base, length in self.pending_columns:
            shape: tuple[int, ...] = () if length is None else (length,)
            if base in TIME_CODES:
                fields.append((key, TIME_CODES[base], (*shape, 2)))
            else:
                fields.append((key, NUMPY_CODES[base], shape))
        run = Run(fields)
        self.decoder.runs.append(run)
        for column in self.waiting.values():
            column.run = run
        self.waiting = {}
        self.pending_columns = []
        return run

    def fixed(self, base: str, length: int | None) -> RunColumn:
        """A fixed-size column in the current run."""
        key = f"f{len(self.pending_columns)}"
        column = RunColumn(self.pa, key, base, length)
        self.waiting[key] = column
        self.pending_columns.append((key, base, length))
        size = (
            np.dtype(TIME_CODES[base]).itemsize * 2
            if base in TIME_CODES
            else np.dtype(NUMPY_CODES[base]).itemsize
        )
        self.size += size * (length or 1)
        return column

    def count(self) -> str:
        self.flush()
        n = self.fresh("n")
        self.line(f"{n}, = {self.ref(_U32.unpack_from, 'u')}(buf, pos)")
        self.line("pos += 4")
        return n

    def message(self, spec: MsgSpec, path: str) -> StructColumn:
        names: list[str] = []
        children: list[Node] = []
        for f in spec.fields:
            names.append(f.name)
            children.append(self.field(f))
        return StructColumn(self.pa, names, children, nested=bool(path))

    def field(self, f: Field) -> Node:
        pa = self.pa
        if f.base in NUMPY_CODES or f.base in TIME_CODES:
            if not f.is_array or f.length is not None:
                return self.fixed(f.base, f.length)
            n = self.count()
            self.ops = None
            if f.base in BYTE_TYPES:
                blobs = BytesColumn(pa)
                self.node(blobs)
                self.line(f"if pos + {n} > end: {self.ref(_short, 'f')}()")
                self.line(f"{self.ref(blobs.counts.append, 'a')}({n})")
                self.line(f"{self.ref(blobs.parts.append, 'a')}(buf[pos:pos + {n}])")
                self.line(f"pos += {n}")
                return blobs
            var = VarArrayColumn(pa, f.base)
            self.node(var)
            self.line(f"{self.ref(var.counts.append, 'a')}({n})")
            self.line(f"{self.ref(var.parts.append, 'a')}(buf[pos:pos + {n} * {var.size}])")
            self.line(f"pos += {n} * {var.size}")
            return var
        if f.base == "string":
            strings = StringColumn(pa, f.is_array, f.length)
            self.node(strings)
            add = self.ref(strings.values.append, "a")
            if f.is_array:
                self.ops = None
                n = str(f.length) if f.length is not None else self.count()
                self.flush()
                if f.length is None:
                    self.line(f"{self.ref(strings.counts.append, 'a')}({n})")
                self.check(n, 4)
                self.line(f"for _ in range({n}):")
                self.indent += "    "
            self.read_string(add)
            if self.ops is not None:
                self.ops.append((strings, 0))
            if f.is_array:
                self.indent = self.indent[:-4]
            return strings
        spec = self.decoder.codec.store.msg(f.base)
        if not f.is_array:
            return self.message(spec, f.name)
        self.ops = None
        n = str(f.length) if f.length is not None else self.count()
        self.flush()
        size = self.decoder.codec.min_size(f.base)
        inner = _Gen(self.decoder, pa)
        inner.env, inner.indent, inner.counter = self.env, self.indent + "    ", self.counter + 100
        inner._names = self._names
        element = inner.message(spec, f.name)
        if not inner.lines[2:] and not inner.pending_columns:  # std_msgs/Empty[]: counts only
            self.line(f"if {n} > {1 << 20}: {self.ref(_short, 'f')}()")
        elif not inner.lines[
            1:
        ]:  # every field fixed: the whole array is one slice of the element's run
            run = inner._new_run()
            self.check(n, size)
            self.line(f"{self.ref(run.parts.append, 'a')}(buf[pos:pos + {n} * {inner.size}])")
            self.line(f"pos += {n} * {inner.size}")
        else:
            inner.flush()
            self.check(n, size)
            self.line(f"for _ in range({n}):")
            self.lines += inner.lines[2:]
        self.counter = inner.counter
        array = MessageArrayColumn(pa, element, f.length)
        self.node(array)
        if f.length is None:
            self.line(f"{self.ref(array.counts.append, 'a')}({n})")
        return array

    def read_string(self, add: str) -> None:
        n = self.count()
        self.line(f"if pos + {n} > end: {self.ref(_short, 'f')}()")
        self.line(f"{add}(str(buf[pos:pos + {n}], 'utf-8', 'replace'))")
        self.line(f"pos += {n}")

    def check(self, count: str, size: int) -> None:
        """A count that cannot fit in what is left is refused before looping over it."""
        if count.isdigit():
            return
        short = self.ref(_short, "f")
        self.line(f"if {count} * {max(size, 1)} > end - pos: {short}()")


__all__: Sequence[str] = ("ColumnDecoder", "arrow_scalar")
