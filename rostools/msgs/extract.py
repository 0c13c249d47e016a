"""Partial decoders: read the numbers one field path names and skip every other byte.

``topic plot`` keeps up with fast topics because it never builds a message. For a path
(``fieldpath.resolve``, the one parser of paths) we generate Python source, as the codec
does, that walks the wire bytes: fixed-size runs are skipped by adding a constant, strings
and arrays of fixed-size elements by their length prefix, and only what varies in size is
looped over. ``/odom/pose/pose/position/x`` is two length reads and one ``unpack_from``.

The value is a plot's number: ints and floats as decoded, ``bool`` as 0 or 1, ``time`` and
``duration`` as float seconds (``to_sec()``); a sliced path gives a list, as
``FieldPath.get`` does. An index past the end of a message's array raises ``IndexError``,
bytes shorter than the type say ``struct.error``; callers decide what either means.
"""

from __future__ import annotations

import struct
from collections.abc import Callable
from typing import Any

from rostools.errors import UsageError
from rostools.msgs.codec import STRUCT_CODES, Codec
from rostools.msgs.codegen import GeneratedCode, element
from rostools.msgs.fieldpath import FieldPath, Step
from rostools.msgs.spec import Field

#: Leaf types a plot can draw.
NUMERIC_TYPES = frozenset(STRUCT_CODES) | {"time", "duration"}

Extractor = Callable[[Any], Any]

_U32 = struct.Struct("<I").unpack_from
_TIME = struct.Struct("<II").unpack_from
_DURATION = struct.Struct("<ii").unpack_from


def _short() -> None:
    raise struct.error("message is shorter than its type says")


def _index_error() -> None:
    raise IndexError("index out of range")


def fixed_size(codec: Codec, f: Field) -> int | None:
    """Bytes field ``f`` always takes on the wire, or None when that depends on the message."""
    if f.is_array and f.length is None:
        return None
    one: int | None
    if f.base == "string":
        one = None
    elif f.base in ("time", "duration"):
        one = 8
    elif f.base in STRUCT_CODES:
        one = struct.calcsize(STRUCT_CODES[f.base])
    else:
        one = fixed_message_size(codec, f.base)
    if one is None:
        return None
    return one * (f.length if f.is_array and f.length is not None else 1)


def fixed_message_size(codec: Codec, name: str) -> int | None:
    """Bytes every message of type ``name`` takes, or None when they vary."""
    cache: dict[str, int | None] = codec.store.cache.setdefault("fixed_sizes", {})
    if name not in cache:
        total: int | None = 0
        for f in codec.store.msg(name).fields:
            size = fixed_size(codec, f)
            if size is None:
                total = None
                break
            assert total is not None
            total += size
        cache[name] = total
    return cache[name]


class _Gen(GeneratedCode):
    """Source of one ``f(buf, pos)`` function; ``off`` is a constant not yet added to pos."""

    def __init__(self, codec: Codec) -> None:
        super().__init__({"_U32": _U32, "_short": _short, "_index": _index_error})
        self.codec = codec
        self.off = 0

    def at(self) -> str:
        return f"pos + {self.off}" if self.off else "pos"

    def flush(self) -> None:
        if self.off:
            self.line(f"pos += {self.off}")
            self.off = 0

    def count(self, f: Field) -> str:
        """The element count of array ``f`` (reads the prefix of a variable one)."""
        if f.length is not None:
            return str(f.length)
        n = self.fresh("n")
        self.line(f"{n}, = _U32(buf, {self.at()})")
        self.off += 4
        return n

    def skip(self, f: Field) -> None:
        size = fixed_size(self.codec, f)
        if size is not None:
            self.off += size
            return
        if not f.is_array:
            if f.base == "string":
                n = self.fresh("n")
                self.line(f"{n}, = _U32(buf, {self.at()})")
                self.line(f"pos += {self.off + 4} + {n}")
                self.off = 0
            else:
                for g in self.codec.store.msg(f.base).fields:
                    self.skip(g)
            return
        n = self.count(f)
        one = element(f.base)
        size = fixed_size(self.codec, one)
        self.flush()
        if size is not None:
            self.line(f"pos += {n} * {size}")
            return
        self.loop(n, one, n)

    def loop(self, n: str, element: Field, bound: str) -> None:
        """Skip ``n`` elements of a variable size (``bound`` of them are in the message)."""
        # Every variable-size element takes at least 4 bytes (a length): a lying count fails
        # here instead of spinning.
        size = max(self.codec.min_size(element.base), 4)
        self.line(f"if {bound} * {size} > len(buf) - pos: _short()")
        self.line(f"for _ in range({n}):")
        self.indent += "    "
        self.skip(element)
        self.flush()
        if self.lines[-1].strip() == f"for _ in range({n}):":
            self.line("pass")
        self.indent = self.indent[:-4]

    def read(self, f: Field) -> str:
        """An expression for the value of scalar field ``f`` at the current position."""
        if f.base in ("time", "duration"):
            unpack = self.ref(_TIME if f.base == "time" else _DURATION)
            s, ns = self.fresh("s"), self.fresh("ns")
            self.line(f"{s}, {ns} = {unpack}(buf, {self.at()})")
            return f"{s} + {ns} / 1e9"
        if f.base not in STRUCT_CODES:
            raise UsageError(f"{f.name} is a {f.type}, not a number")
        unpack = self.ref(struct.Struct("<" + STRUCT_CODES[f.base]).unpack_from)
        suffix = " + 0" if f.base == "bool" else ""  # True -> 1: a number, as plots want
        return f"{unpack}(buf, {self.at()})[0]{suffix}"

    def walk(self, type_name: str, steps: tuple[Step, ...]) -> None:
        """Code that returns the value at ``steps`` in a message of ``type_name``."""
        step, rest = steps[0], steps[1:]
        fields = self.codec.store.msg(type_name).fields
        found = next(i for i, g in enumerate(fields) if g.name == step.name)
        for g in fields[:found]:
            self.skip(g)
        f = fields[found]
        if step.index is None:
            if rest:
                self.walk(f.base, rest)
            else:
                self.line(f"return {self.read(f)}")
            return
        n = self.count(f)
        element = Field(f.name, f.base, f.base, False, None)
        size = fixed_size(self.codec, element)
        if isinstance(step.index, int):
            i = self.fresh("i")
            self.line(f"{i} = {step.index} + {n} if {step.index} < 0 else {step.index}")
            self.line(f"if not 0 <= {i} < {n}: _index()")
            if size is not None:
                self.flush()
                self.line(f"pos += {i} * {size}")
            else:
                self.flush()
                self.loop(i, element, n)
            if rest:
                self.walk(element.base, rest)
            else:
                self.line(f"return {self.read(element)}")
            return
        picked = self.ref(step.index)
        if not rest and element.base in STRUCT_CODES:
            code = STRUCT_CODES[element.base]
            unpack = self.ref(struct.unpack_from)
            self.line(f"if {n} * {size} > len(buf) - ({self.at()}): _short()")
            values = f"{unpack}('<%d{code}' % {n}, buf, {self.at()})[{picked}]"
            plus = " + 0" if element.base == "bool" else ""
            self.line(f"return [v{plus} for v in {values}]")
            return
        sub = self.ref(_compile(self.codec, element, rest))
        self.flush()
        if size is not None:
            self.line(f"if {n} * {size} > len(buf) - pos: _short()")
            self.line(f"return [{sub}(buf, pos + k * {size}) for k in range({n})[{picked}]]")
            return
        starts = self.fresh("starts")
        self.line(f"{starts} = []")
        self.line(f"if {n} * 4 > len(buf) - pos: _short()")
        self.line(f"for _ in range({n}):")
        self.indent += "    "
        self.line(f"{starts}.append(pos)")
        self.skip(element)
        self.flush()
        self.indent = self.indent[:-4]
        self.line(f"return [{sub}(buf, p) for p in {starts}[{picked}]]")

    def extractor(self, name: str) -> Callable[..., Any]:
        fn: Callable[..., Any] = self.compile("extract(buf, pos=0)", "extract", name, bind=True)
        return fn


def _compile(codec: Codec, element: Field, steps: tuple[Step, ...]) -> Callable[[Any, int], Any]:
    """``f(buf, pos)``: the value at ``steps`` in the element that starts at ``pos``."""
    gen = _Gen(codec)
    if steps:
        gen.walk(element.base, steps)
    else:
        gen.line(f"return {gen.read(element)}")
    return gen.extractor(element.base)


def extractor(codec: Codec, type_name: str, path: FieldPath, name: str = "") -> Extractor:
    """``extract(buf)``: the number (or list, for a slice) at ``path`` in one raw message.

    ``path`` must be resolved against ``type_name`` in ``codec``'s store and end in a number
    (``NUMERIC_TYPES``); anything else is a ``UsageError`` naming the path (as ``name``, if
    given: the topic and path the user wrote).
    """
    if path.result.base not in NUMERIC_TYPES or (path.result.is_array and not _sliced(path)):
        raise UsageError(
            f"{name or path.text} is a {path.result.type}, not a number",
            hint="plot a numeric field, or slice an array of numbers: ranges[0:5]",
        )
    if not path.steps:
        raise UsageError("give a field to plot after the topic")
    gen = _Gen(codec)
    gen.walk(type_name, path.steps)
    # ``pos`` defaults to 0: called with the message alone, with no wrapper in between
    return gen.extractor(f"{type_name}/{path.text}")


def _sliced(path: FieldPath) -> bool:
    return any(isinstance(s.index, slice) for s in path.steps)
