"""ROS 1 message bytes to ROS 2 CDR bytes, by a function generated per type.

As the codec does for ROS 1 (``msgs/codec.py``), each type gets the Python source of one
function, compiled once (``msgs.codegen.GeneratedCode``): no Python object per message. The
function walks the ROS 1 bytes and appends the CDR (little-endian, XCDR1 as ROS 2 writes it)
to a ``bytearray`` that starts with the encapsulation header ``00 01 00 00`` (an *appender*,
the same function over a given buffer, lets ``bag convert --to ros2`` write into the MCAP's
open chunk, a big byte run such as an image's passed on by reference):

- runs of fixed-size fields are copied as slices of the input, with the padding CDR wants
  between them: where the output's offset is known at generation time (modulo 8, 4 or 2) the
  padding is a constant, else it is computed from ``len(out)`` once and the offset is known
  again;
- a string gains its NUL (the count includes it), a sequence's count is copied, and a
  sequence of primitives is aligned to its element only when it is not empty (as rosbags and
  Fast-CDR write it); nothing pads the end of a message;
- the types themselves are rosbags' field descriptions: the source's as parsed from the ROS 1
  definition (``time`` already ``builtin_interfaces/msg/Time``), the target's from the ROS 2
  type store (``ros2types``).

Where the two differ, the rules are rosbags-convert's (its ``migrate_message``): fields are
matched by name (a ROS 2 field that is new takes a removed ROS 1 field of the same type, so
``D`` becomes ``d``), a field ROS 2 added gets its default (zero, empty), a field it removed is
skipped (``std_msgs/Header``'s ``seq``), numbers change type by value, a fixed array is cut or
padded to its ROS 2 length and a bounded sequence cut to its bound. Fields whose order the
mapping would change cannot be streamed: ``ReorderedFieldsError`` names the type.
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Sequence
from typing import Any

from rostools.bag.formats.sink import BIG_PAYLOAD
from rostools.errors import InvalidDataError
from rostools.msgs.codegen import GeneratedCode

#: rosbags' ``Nodetype`` values (read here without importing rosbags).
BASE, NAME, ARRAY, SEQUENCE = 1, 2, 3, 4
SIZES = {
    "bool": 1, "int8": 1, "uint8": 1, "byte": 1, "char": 1, "int16": 2, "uint16": 2,
    "int32": 4, "uint32": 4, "int64": 8, "uint64": 8, "float32": 4, "float64": 8,
}  # fmt: skip
CODES = {
    "bool": "?", "int8": "b", "uint8": "B", "byte": "B", "char": "B", "int16": "h",
    "uint16": "H", "int32": "i", "uint32": "I", "int64": "q", "uint64": "Q",
    "float32": "f", "float64": "d",
}  # fmt: skip
#: ROS 2 gives an empty message this one-byte field; its ROS 1 twin has no bytes at all.
PLACEHOLDER = "structure_needs_at_least_one_member"
HEADER = "std_msgs/msg/Header"
ENCAPSULATION = b"\x00\x01\x00\x00"  # CDR, little-endian, no options
_U32 = struct.Struct("<I")
_ZEROS = tuple(bytes(n) for n in range(8))
_NUL_PADS = tuple(bytes(n + 1) for n in range(8))  # a string's NUL, then n bytes of padding
#: What a generated converter raises on input shorter than its counts say.
_SHORT = (struct.error, IndexError, ValueError, OverflowError, MemoryError)

Desc = tuple[Any, ...]
FieldList = Sequence[tuple[str, Desc]]
#: A type's fields by name (rosbags' ``fielddefs[name][1]``).
Lookup = Callable[[str], FieldList]


class ConversionError(InvalidDataError):
    """ROS 1 bytes that do not convert: shorter or longer than their type says."""


class ReorderedFieldsError(InvalidDataError):
    """A type whose ROS 2 twin takes its fields in another order than ROS 1 gives them."""


def _mismatch(pos: int, size: int) -> None:
    if pos > size:
        raise ConversionError("message is shorter than its type says")
    raise ConversionError(f"message has {size - pos} bytes more than its type says")


def _numbers(buf: Any, pos: int, n: int, src: str, dst: str) -> bytes:
    """``n`` numbers read as ``src`` codes, written as ``dst`` (a field whose type changed)."""
    values = struct.unpack_from(f"<{n}{src}", buf, pos)
    if dst in "bBhHiIqQ" and src in "fd":
        values = tuple(int(v) for v in values)
    try:
        return struct.pack(f"<{n}{dst}", *values)
    except struct.error as err:
        raise ConversionError(f"a value does not fit its ROS 2 type ({err})") from None


def _fields(lookup: Lookup, name: str) -> list[tuple[str, Desc]]:
    return [f for f in lookup(name) if f[0] != PLACEHOLDER]


def same_wire(src: Lookup, dst: Lookup, sname: str, dname: str) -> bool:
    """True when the two types' fields match one for one, names aside (rosbags' test)."""
    if sname == HEADER:
        return False  # ROS 1's has seq: matched by name, it is dropped
    sfields, dfields = src(sname), dst(dname)
    if len(sfields) != len(dfields):
        return False
    for (_, s), (_, d) in zip(sfields, dfields, strict=True):
        if s != d:
            return False
        sub_s = s[1][0] if s[0] in (ARRAY, SEQUENCE) else s
        sub_d = d[1][0] if d[0] in (ARRAY, SEQUENCE) else d
        if sub_s[0] == NAME and not same_wire(src, dst, sub_s[1], sub_d[1]):
            return False
    return True


def plan(src: Lookup, dst: Lookup, sname: str, dname: str) -> list[tuple[Desc, int | None]]:
    """For each ROS 2 field, its ROS 2 description and the index of its ROS 1 field (or None).

    ``ReorderedFieldsError`` when the ROS 1 fields would not be read in their order.
    """
    sfields, dfields = _fields(src, sname), _fields(dst, dname)
    if same_wire(src, dst, sname, dname):
        return [(d, i) for i, (_, d) in enumerate(dfields)]
    index = {n: i for i, (n, _) in enumerate(sfields)}
    dnames = {n for n, _ in dfields}
    removed = [n for n, _ in sfields if n not in dnames]
    chosen: list[tuple[Desc, int | None]] = []
    for name, desc in dfields:
        if name in index:
            chosen.append((desc, index[name]))
            continue
        match = next((r for r in removed if sfields[index[r]][1] == desc), None)
        if match is not None:
            removed.remove(match)
        chosen.append((desc, None if match is None else index[match]))
    order = [i for _, i in chosen if i is not None]
    if order != sorted(order):
        raise ReorderedFieldsError(f"{dname} takes the fields of ROS 1's {sname} in another order")
    return chosen


def _meet(a: tuple[int, int], b: tuple[int, int]) -> tuple[int, int]:
    """What two states of knowledge of the offset (``r`` modulo ``m``) both say."""
    m = min(a[1], b[1])
    while m > 1 and (a[0] - b[0]) % m:
        m //= 2
    return a[0] % m, m


def _at(off: int) -> str:
    """``pos`` moved by ``off`` bytes, as source."""
    return f"pos + {off}" if off else "pos"


def _kind(desc: Desc) -> str:
    """``string``, ``number`` or ``message``: what an element is, for matching two fields."""
    if desc[0] == NAME:
        return "message"
    return "string" if desc[1][0] == "string" else "number"


class _Gen(GeneratedCode):
    """The source of one function over ``buf``/``pos`` (ROS 1 in) and ``out`` (CDR out).

    ``r``/``m``: the output's CDR offset is ``r`` modulo ``m`` (1, 2, 4 or 8), where known.
    ``pending``: what is still to be appended, as (start, end) slices of ``buf`` relative to
    ``pos`` or literal bytes; ``off``: how far ``pos`` has moved since it was last written.
    """

    def __init__(self, conv: Converters, r: int = 0, m: int = 1, *, into: bool = False) -> None:
        super().__init__(
            {"_Z": _ZEROS, "_u32": _U32.unpack_from, "_p32": _U32.pack, "_BIG": BIG_PAYLOAD}
        )
        self.conv = conv
        self.into = into
        # Where the CDR starts in ``out``, modulo 8: 4 past the header of a fresh ``out``;
        # an appender is told (``b``), and moves it when a big run leaves ``out``.
        self.base = "b" if into else "4"
        self.r, self.m = r, m
        self.pending: list[tuple[int, int] | bytes] = []
        self.off = 0

    # -- the output's offset and what is pending ---------------------------------------

    def advance(self, n: int) -> None:
        self.r = (self.r + n) % self.m

    def copy(self, n: int) -> None:
        if n:
            self.pending.append((self.off, self.off + n))
            self.off += n
            self.advance(n)

    def literal(self, data: bytes) -> None:
        if data:
            self.pending.append(data)
            self.advance(len(data))

    def align(self, a: int) -> None:
        if a <= 1:
            return
        if a <= self.m:
            self.literal(bytes(-self.r % a))
            return
        self.flush(move=False)
        self.line(f"out += _Z[({self.base} - len(out)) & {a - 1}]")
        self.r, self.m = 0, a

    def unknown(self) -> None:
        self.r, self.m = 0, 1

    def flush(self, *, move: bool = True) -> None:
        """Write what is pending; ``move``: and bring ``pos`` up to ``off``."""
        merged: list[tuple[int, int] | bytes] = []
        for piece in self.pending:
            last = merged[-1] if merged else None
            if isinstance(piece, tuple) and isinstance(last, tuple) and last[1] == piece[0]:
                merged[-1] = (last[0], piece[1])
            elif isinstance(piece, bytes) and isinstance(last, bytes):
                merged[-1] = last + piece
            else:
                merged.append(piece)
        for piece in merged:
            if isinstance(piece, bytes):
                self.line(f"out += {piece!r}")
            else:
                self.line(f"out += buf[{_at(piece[0])}:pos + {piece[1]}]")
        self.pending = []
        if move:
            if self.off:
                self.line(f"pos += {self.off}")
            self.off = 0

    def move(self, expr: str) -> None:
        """Write what is pending and move ``pos`` past ``off`` and ``expr`` more bytes."""
        self.flush(move=False)
        self.line(f"pos += {self.off} + {expr}" if self.off else f"pos += {expr}")
        self.off = 0

    def count(self) -> str:
        """Read a ROS 1 count (u32) into a fresh local; ``off`` passes it."""
        self.flush(move=False)
        n = self.fresh("n")
        self.line(f"{n}, = _u32(buf, {_at(self.off)})")
        self.off += 4
        return n

    def loop(self, count: str, body: Callable[[], None]) -> None:
        """``body`` ``count`` times.

        What is known of the offset at the body's start must hold at every iteration's: the
        body is generated again, knowing less, until it does.
        """
        self.flush()
        self.line(f"for _ in range({count}):")
        self.indent += "    "
        entry = state = (self.r, self.m)
        mark = len(self.lines)
        while True:
            del self.lines[mark:]
            self.r, self.m = state
            body()
            self.flush()
            again = _meet(state, (self.r, self.m))
            if again == state:
                break
            state = again
        if len(self.lines) == mark:
            self.line("pass")
        self.indent = self.indent[:-4]
        self.r, self.m = _meet(entry, (self.r, self.m))  # none, or some iterations

    # -- one field: ROS 1 ``s`` in, ROS 2 ``d`` out -------------------------------------

    def message(self, sname: str, dname: str) -> None:
        conv = self.conv
        sfields = _fields(conv.src, sname)
        if not _fields(conv.dst, dname):  # an empty ROS 2 message: its one byte
            for _, s in sfields:
                self.skip(s)
            self.literal(b"\x00")
            return
        at = 0
        for d, i in conv.plan(sname, dname):
            if i is None:
                self.default(d)
                continue
            for _, s in sfields[at:i]:
                self.skip(s)
            self.field(sfields[i][1], d)
            at = i + 1
        for _, s in sfields[at:]:
            self.skip(s)

    def field(self, s: Desc, d: Desc) -> None:
        if d[0] in (ARRAY, SEQUENCE):
            if s[0] in (ARRAY, SEQUENCE) and _kind(s[1][0]) == _kind(d[1][0]):
                self.array(s, d)
                return
        elif s[0] == d[0] == NAME:
            self.message(s[1], d[1])
            return
        elif s[0] == d[0] == BASE and _kind(s) == _kind(d):
            self.scalar(s[1][0], d[1][0])
            return
        self.skip(s)  # a field whose kind changed: ROS 2's default, as rosbags gives
        self.default(d)

    def scalar(self, s: str, d: str) -> None:
        if d == "string":
            self.string()
            return
        size = SIZES[d]
        self.align(size)
        if s == d or (SIZES[s] == size and "float" not in s + d):
            self.copy(size)
            return
        self.flush(move=False)
        fn = self.ref(_numbers, "f")
        self.line(f"out += {fn}(buf, pos + {self.off}, 1, {CODES[s]!r}, {CODES[d]!r})")
        self.off += SIZES[s]
        self.advance(size)

    def string(self) -> None:
        self.align(4)
        n = self.count()
        at = self.off
        self.line(f"out += _p32({n} + 1)")
        self.line(f"out += buf[{_at(at)}:{_at(at)} + {n}]")
        self.line("out.append(0)")
        self.move(n)
        self.unknown()

    def array(self, s: Desc, d: Desc) -> None:
        ssub, dsub = s[1][0], d[1][0]
        fixed_src = s[0] == ARRAY
        if d[0] == SEQUENCE:
            self.align(4)
        if fixed_src:
            n: str | int = int(s[1][1])
        else:
            n = self.count()
        bound = int(d[1][1]) if d[1][1] else None
        if d[0] == ARRAY:
            k: str | int = min(n, bound) if isinstance(n, int) and bound else n
        else:
            k = min(n, bound) if isinstance(n, int) and bound else n
        if bound and not isinstance(n, int):
            k = self.fresh("k")
            self.line(f"{k} = min({n}, {bound})")
        if d[0] == SEQUENCE:
            if isinstance(k, int):
                self.literal(_U32.pack(k))
            else:
                self.flush(move=False)
                self.line(f"out += _p32({k})")
                self.advance(4)
        if _kind(dsub) == "number":
            self.numbers(ssub[1][0], dsub[1][0], n, k, bound if d[0] == ARRAY else None, d[0])
            return
        self.loop(str(k), lambda: self.field(ssub, dsub))  # inline: no call per element
        if n != k:
            skip = self.ref(self.conv.skipper(ssub), "s")
            self.line(f"for _ in range({n} - {k}): pos = {skip}(buf, pos)")
        if d[0] == ARRAY and bound and k != bound:
            fill = self.ref(self.conv.filler(dsub), "d")
            self.line(f"for _ in range({bound} - {k}): {fill}(out, {self.base})")
        self.unknown()

    def numbers(
        self, s: str, d: str, n: str | int, k: str | int, size: int | None, kind: int
    ) -> None:
        """A run of numbers: ``k`` of ``n`` converted, padded with zeros to ``size`` if fixed."""
        es, ss = SIZES[d], SIZES[s]
        same = s == d or (ss == es and "float" not in s + d)
        static = isinstance(n, int) and isinstance(k, int)
        if kind == ARRAY or (isinstance(k, int) and k):
            self.align(es)
        elif es > 1:  # a sequence aligns to its element only when it is not empty
            self.flush(move=False)
            if self.m >= es:
                pad = -self.r % es
                if pad:
                    self.line(f"if {k}: out += {bytes(pad)!r}")
            else:
                self.line(f"if {k}: out += _Z[({self.base} - len(out)) & {es - 1}]")
        start = (self.r, self.m)
        if static and same:
            assert isinstance(n, int) and isinstance(k, int)
            self.copy(k * es)
            self.off += (n - k) * ss
        else:
            self.flush(move=False)
            at = self.off
            if same and self.into:
                self.run(f"pos + {at}", f"{k} * {es}")
            elif same:
                self.line(f"out += buf[pos + {at}:pos + {at} + {k} * {es}]")
            else:
                fn = self.ref(_numbers, "f")
                self.line(f"out += {fn}(buf, pos + {at}, {k}, {CODES[s]!r}, {CODES[d]!r})")
            self.move(f"{n} * {ss}")
        if size is not None:
            if isinstance(k, int):
                self.literal(bytes((size - k) * es))
            else:
                self.flush(move=False)
                self.line(f"out += bytes(({size} - {k}) * {es})")
        if kind == ARRAY:  # a fixed length: the offset moved by what it holds
            self.r, self.m = start
            self.advance(int(size or 0) * es)
        elif es > 1:  # after the count (4-aligned): empty, or aligned to es and whole ones
            self.r, self.m = 0, min(es, 4)
        else:
            self.unknown()

    def nul_and_pad(self) -> None:
        """A string's NUL and the padding after it appended at once (one step less)."""
        lines = self.lines
        pad = f"out += _Z[({self.base} - len(out)) & "
        for i in range(len(lines) - 2, 0, -1):
            nul = lines[i - 1]
            if not nul.endswith("out.append(0)"):
                continue
            indent = nul[: -len("out.append(0)")]
            moved = lines[i].startswith(indent + "pos += ")
            j = i + 1 if moved else i
            if j < len(lines) and lines[j].startswith(indent + pad):
                mask = lines[j][len(indent + pad) :]
                merged = f"{indent}out += _N[({self.base} - 1 - len(out)) & {mask}"
                lines[i - 1 : j + 1] = [lines[i], merged] if moved else [merged]
        self.env.setdefault("_N", _NUL_PADS)

    def run(self, at: str, size: str) -> None:
        """``size`` bytes from ``at`` as they are; in an appender, a big run by reference.

        ``cut(out, buf, start, end)`` takes ``out`` and the run and gives the ``out`` to go on
        with (``McapWriter.store_stream``): an image is never copied by Python.
        """
        c = self.fresh("c")
        self.line(f"{c} = {size}")
        self.line(f"if {c} >= _BIG and {at} + {c} <= len(buf):")
        self.line(f"    b -= len(out) + {c}")
        self.line(f"    out = cut(out, buf, {at}, {at} + {c})")
        self.line("    b += len(out)")  # what the new buffer starts with
        self.line("else:")
        self.line(f"    out += buf[{at}:{at} + {c}]")

    # -- fields ROS 2 does not have: skipped; fields ROS 1 did not have: defaults ------

    def skip(self, s: Desc) -> None:
        if s[0] == BASE:
            if s[1][0] == "string":
                self.move(self.count())
            else:
                self.off += SIZES[s[1][0]]
        elif s[0] == NAME:
            for _, f in _fields(self.conv.src, s[1]):
                self.skip(f)
        else:
            sub = s[1][0]
            n = str(s[1][1]) if s[0] == ARRAY else self.count()
            if sub[0] == BASE and sub[1][0] != "string":
                self.move(f"{n} * {SIZES[sub[1][0]]}")
            else:
                skip = self.conv.skipper(sub)
                self.flush()
                self.line(f"for _ in range({n}): pos = {self.ref(skip, 's')}(buf, pos)")

    def default(self, d: Desc) -> None:
        if d[0] == BASE:
            if d[1][0] == "string":
                self.align(4)
                self.literal(b"\x01\x00\x00\x00\x00")
            else:
                self.align(SIZES[d[1][0]])
                self.literal(bytes(SIZES[d[1][0]]))
        elif d[0] == NAME:
            fields = _fields(self.conv.dst, d[1])
            if not fields:
                self.literal(b"\x00")
            for _, f in fields:
                self.default(f)
        elif d[0] == SEQUENCE:
            self.align(4)
            self.literal(bytes(4))
        else:
            for _ in range(int(d[1][1])):
                self.default(d[1][0])


class Converters:
    """The generated converters between one ROS 1 type store and one ROS 2 type store.

    ``src`` and ``dst`` give a type's fields (rosbags' descriptions); ``converter`` compiles,
    once per pair of names, ``f(buf) -> bytearray``: the CDR of one ROS 1 message.
    """

    def __init__(self, src: Lookup, dst: Lookup) -> None:
        self.src, self.dst = src, dst
        self._plans: dict[tuple[str, str], list[tuple[Desc, int | None]]] = {}
        self._done: dict[tuple[str, ...], Callable[..., Any]] = {}

    def plan(self, sname: str, dname: str) -> list[tuple[Desc, int | None]]:
        """``plan`` for the pair, cached."""
        key = (sname, dname)
        found = self._plans.get(key)
        if found is None:
            found = self._plans[key] = plan(self.src, self.dst, sname, dname)
        return found

    def check(self, sname: str, dname: str) -> None:
        """Raise ``ReorderedFieldsError`` now for any pair the conversion would meet."""
        for d, i in self.plan(sname, dname):
            if i is None:
                continue
            s = _fields(self.src, sname)[i][1]
            s = s[1][0] if s[0] in (ARRAY, SEQUENCE) else s
            d = d[1][0] if d[0] in (ARRAY, SEQUENCE) else d
            if s[0] == d[0] == NAME:
                self.check(s[1], d[1])

    def converter(self, sname: str, dname: str) -> Callable[[Any], bytearray]:
        """The CDR (encapsulation header first) of one ROS 1 message of ``sname``."""
        return self._top(sname, dname, into=False)

    def appender(self, sname: str, dname: str) -> Callable[..., bytearray]:
        """``f(buf, out, b, cut) -> out``: ``converter``'s bytes appended to ``out``.

        ``b`` is ``len(out) + 4`` (where the CDR will start, past its header); a run of at
        least ``sink.BIG_PAYLOAD`` bytes copied as it is goes to ``cut(out, buf, start, end)``,
        whose result the rest is appended to (and returned). On ``ConversionError``, ``out``
        holds part of the message: the caller cuts it off.
        """
        return self._top(sname, dname, into=True)

    def _top(self, sname: str, dname: str, *, into: bool) -> Callable[..., bytearray]:
        key = ("into" if into else "top", sname, dname)
        fn = self._done.get(key)
        if fn is None:
            self.check(sname, dname)
            gen = _Gen(self, 0, 8, into=into)
            gen.line(f"out += {ENCAPSULATION!r}" if into else f"out = bytearray({ENCAPSULATION!r})")
            gen.line("pos = 0")
            gen.line("try:")  # free until raised (3.11): short input is one error, named
            gen.indent += "    "
            gen.message(sname, dname)
            gen.flush()
            gen.indent = gen.indent[:-4]
            gen.line(f"except {gen.ref(_SHORT, 'x')}:")
            gen.line(f"    {gen.ref(_mismatch, 'f')}(len(buf) + 1, len(buf))")
            gen.line(f"if pos != len(buf): {gen.ref(_mismatch, 'f')}(pos, len(buf))")
            gen.line("return out")
            gen.nul_and_pad()
            signature = "append(buf, out, b, cut)" if into else "convert(buf)"
            fn = gen.compile(signature, "ros1->cdr", dname, bind=True)
            self._done[key] = fn
        return fn

    def skipper(self, s: Desc) -> Callable[..., Any]:
        """``f(buf, pos) -> pos``: past one ROS 1 element."""
        key = ("skip", repr(s))
        fn = self._done.get(key)
        if fn is None:
            gen = _Gen(self)
            gen.skip(s)
            gen.flush()
            gen.line("return pos")
            name = s[1] if s[0] == NAME else s[1][0]
            fn = self._done[key] = gen.compile("skip(buf, pos)", "ros1 skip", name, bind=True)
        return fn

    def filler(self, d: Desc) -> Callable[..., Any]:
        """``f(out, b)``: one ROS 2 element's default appended (``b``: ``appender``'s)."""
        key = ("default", repr(d))
        fn = self._done.get(key)
        if fn is None:
            gen = _Gen(self)
            gen.base = "b"  # the caller's
            gen.line("buf = b''")
            gen.line("pos = 0")
            gen.default(d)
            gen.flush()
            name = d[1] if d[0] == NAME else d[1][0]
            fn = self._done[key] = gen.compile("fill(out, b)", "cdr default", name, bind=True)
        return fn
