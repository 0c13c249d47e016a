"""Messages as plain data (dicts and lists), JSON lines and ``rostopic echo -p`` CSV.

``to_plain`` is generated per type like the text formatter. JSON has one object per message;
times are ``{"secs", "nsecs"}`` objects and ``uint8[]`` is a list of numbers, as in the text
output. CSV follows ``rostopic echo -p``: a ``%time,field.…`` header from the first message,
arrays spread over ``field.name0, field.name1, …`` columns, bools as 1/0, times in
nanoseconds; unlike rostopic it keeps ``uint8[]``/``char[]`` columns instead of dropping them.
"""

from __future__ import annotations

import binascii
import json
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from rostools.msgs.codec import BYTE_TYPES, STRUCT_CODES, Codec
from rostools.msgs.codegen import GeneratedCode, attr_name, element
from rostools.msgs.message import Time
from rostools.msgs.spec import Field, MsgSpec

Plain = Callable[[Any], Any]


class _PlainGen(GeneratedCode):
    kind = "plain"

    def __init__(self, codec: Codec) -> None:
        super().__init__({"_list": list})
        self.codec = codec

    def message(self, spec: MsgSpec, expr: str) -> str:
        """A message's expression; a big type's in parts, each a function (as the codec)."""
        if self.codec.inline(spec.name):
            return self.whole(self.members(spec.fields, expr))
        calls = []
        for i, part in enumerate(self.codec.parts(spec)):
            gen = type(self)(self.codec)
            gen.line("return " + gen.part(gen.members(part, "m")))
            fn = gen.compile("part(m)", self.kind, f"{spec.name} part {i}")
            calls.append(self.call(self.ref(fn), expr))
        return self.whole(self.joined(calls))

    def members(self, fields: Sequence[Field], expr: str) -> str:
        return ", ".join(
            f"{f.name!r}: {self.value(f, f'{expr}.{attr_name(f.name)}')}" for f in fields
        )

    def whole(self, members: str) -> str:
        return "{" + members + "}"

    def part(self, members: str) -> str:
        return "{" + members + "}"

    def call(self, fn: str, expr: str) -> str:
        return f"**{fn}({expr})"

    def joined(self, calls: list[str]) -> str:
        return ", ".join(calls)

    def value(self, f: Field, expr: str) -> str:
        if f.is_array:
            if f.base in BYTE_TYPES or f.base in STRUCT_CODES or f.base == "string":
                return f"_list({expr})"
            item = to_plain(self.codec, element(f.base))
            return f"[{self.ref(item)}(v) for v in {expr}]"
        if f.base in ("time", "duration"):
            return f"{{'secs': {expr}.secs, 'nsecs': {expr}.nsecs}}"
        if f.base in STRUCT_CODES or f.base == "string":
            return expr
        return self.message(self.codec.store.msg(f.base), expr)


def to_plain(codec: Codec, value_type: Field) -> Plain:
    """``plain(value)``: the value as dicts, lists and scalars (generated per type)."""
    fn: Plain = _generated(codec, value_type, _PlainGen(codec), "plain", "{}")
    return fn


def _generated(codec: Codec, value_type: Field, gen: _PlainGen, kind: str, wrap: str) -> Any:
    """``def <kind>(m): return <wrap around gen's expression>``, compiled once per type."""
    key = (kind, value_type.type, value_type.is_array)
    fn = codec.store.cache.get(key)
    if fn is None:
        gen.line("return " + wrap.replace("{}", gen.value(value_type, "m")))
        fn = codec.store.cache[key] = gen.compile(f"{kind}(m)", kind, value_type.type)
    return fn


def _json_float(v: float) -> str:
    """A float as ``dumps`` writes it: its repr, or "nan"/"inf"/"-inf" as strings."""
    if math.isfinite(v):
        return repr(v)
    return '"nan"' if math.isnan(v) else ('"inf"' if v > 0 else '"-inf"')


def _json_bool(v: bool) -> str:
    return "true" if v else "false"


def _json_floats(values: Any) -> str:
    return "[" + ",".join(map(_json_float, values)) + "]"


def _json_ints(values: Any) -> str:
    return "[" + ",".join(map(str, values)) + "]"


def _json_bools(values: Any) -> str:
    return "[" + ",".join(map(_json_bool, values)) + "]"


def _json_each(item: Callable[[Any], str], values: Any) -> str:
    return "[" + ",".join(map(item, values)) + "]"


class _JsonGen(_PlainGen):
    """Writes the JSON text ``dumps(plain(value))`` would, without the dicts in between."""

    kind = "json"

    def __init__(self, codec: Codec) -> None:
        super().__init__(codec)
        from json.encoder import encode_basestring  # the C escaper json uses, not ASCII-only

        self.env.update(
            _s=encode_basestring, _f=_json_float, _fs=_json_floats, _is=_json_ints,
            _bs=_json_bools, _each=_json_each, _b=_json_bool,
        )  # fmt: skip

    def value(self, f: Field, expr: str) -> str:
        """An f-string fragment (inside ``f'...'``) that writes ``expr`` as JSON."""
        if f.is_array:
            if f.base == "bool":
                return f"{{_bs({expr})}}"
            if f.base in ("float32", "float64"):
                return f"{{_fs({expr})}}"
            if f.base in STRUCT_CODES:  # integers, and uint8[]/char[] bytes as numbers
                return f"{{_is({expr})}}"
            if f.base == "string":
                return f"{{_each(_s, {expr})}}"
            item = to_json(self.codec, element(f.base))
            return f"{{_each({self.ref(item)}, {expr})}}"
        if f.base in ("time", "duration"):
            return f'{{{{"secs":{{{expr}.secs}},"nsecs":{{{expr}.nsecs}}}}}}'
        if f.base == "bool":
            return f"{{_b({expr})}}"
        if f.base in ("float32", "float64"):
            return f"{{_f({expr})}}"
        if f.base in STRUCT_CODES:
            return f"{{{expr}}}"
        if f.base == "string":
            return f"{{_s({expr})}}"
        return self.message(self.codec.store.msg(f.base), expr)

    def members(self, fields: Sequence[Field], expr: str) -> str:
        return ",".join(
            f'"{f.name}":{self.value(f, f"{expr}.{attr_name(f.name)}")}' for f in fields
        )

    def whole(self, members: str) -> str:
        return "{{" + members + "}}"

    def part(self, members: str) -> str:
        return "f'" + members + "'"

    def call(self, fn: str, expr: str) -> str:
        return f"{{{fn}({expr})}}"

    def joined(self, calls: list[str]) -> str:
        return ",".join(calls)


def to_json(codec: Codec, value_type: Field) -> Callable[[Any], str]:
    """``text(value)``: the same text as ``dumps(to_plain(...)(value))``, generated per type."""
    fn: Callable[[Any], str] = _generated(codec, value_type, _JsonGen(codec), "json", "f'{}'")
    return fn


def _rosbridge_float(v: float) -> str:
    """A float as rosbridge's ``json.dumps`` writes it: NaN and infinities as JS tokens."""
    if math.isfinite(v):
        return repr(v)
    return "NaN" if math.isnan(v) else ("Infinity" if v > 0 else "-Infinity")


def _base64(values: Any) -> str:
    """Standard base64 of a byte array (bytes, or a list of ints), as rosbridge writes it."""
    data = values if isinstance(values, bytes | bytearray | memoryview) else bytes(values)
    return binascii.b2a_base64(data, newline=False).decode("ascii")


class _RosbridgeGen(_JsonGen):
    """rosbridge_server's JSON of a message, as ``json.dumps`` of its ``extract_values``.

    ``uint8[]``/``char[]`` as base64, strings escaped to ASCII, NaN and infinities as the
    tokens ``NaN`` and ``Infinity``.
    """

    kind = "rosbridge"

    def __init__(self, codec: Codec) -> None:
        super().__init__(codec)
        from json.encoder import encode_basestring_ascii

        self.env.update(
            _s=encode_basestring_ascii, _f=_rosbridge_float, _b64=_base64,
            _fs=lambda vs: "[" + ",".join(map(_rosbridge_float, vs)) + "]",
        )  # fmt: skip

    def value(self, f: Field, expr: str) -> str:
        """As JSON's, but bytes as base64 and nested types in rosbridge's JSON."""
        if f.is_array and f.base in BYTE_TYPES:
            return f'"{{_b64({expr})}}"'  # the quotes in the template: no copy to add them
        if f.is_array and f.base not in STRUCT_CODES and f.base not in _WRITTEN:
            item = to_rosbridge_json(self.codec, element(f.base))
            return f"{{_each({self.ref(item)}, {expr})}}"
        return super().value(f, expr)


#: Array element types the JSON writer writes itself (the rest are messages).
_WRITTEN = ("bool", "float32", "float64", "string", "time", "duration")


def to_rosbridge_json(codec: Codec, value_type: Field) -> Callable[[Any], str]:
    """``text(value)``: a message as rosbridge_server writes it in JSON, generated per type."""
    gen = _RosbridgeGen(codec)
    fn: Callable[[Any], str] = _generated(codec, value_type, gen, "rosbridge", "f'{}'")
    return fn


def _finite(value: Any) -> Any:
    """Non-finite floats as the strings "nan", "inf", "-inf": JSON has no other spelling."""
    if isinstance(value, float) and not math.isfinite(value):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
    if isinstance(value, dict):
        return {k: _finite(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_finite(v) for v in value]
    return value


#: One encoder for every call: ``json.dumps`` with options builds a new one each time.
_ENCODE = json.JSONEncoder(
    separators=(",", ":"), ensure_ascii=False, allow_nan=False, default=str
).encode


def dumps(value: Any) -> str:
    """Compact JSON text of plain data, always valid JSON (anything else as its ``str``)."""
    try:
        return _ENCODE(value)
    except ValueError:
        return json.dumps(_finite(value), separators=(",", ":"), ensure_ascii=False, default=str)


@dataclass(frozen=True)
class CsvOptions:
    """``--nostr`` drops string columns, ``--noarr`` array columns (as ``rostopic echo -p``)."""

    nostr: bool = False
    noarr: bool = False

    def keep(self, f: Field) -> bool:
        """Whether a field's columns are printed."""
        return not (self.noarr and "[" in f.type) and not (self.nostr and "string" in f.type)


def csv_header(codec: Codec, value_type: Field, value: Any, options: CsvOptions) -> str:
    """The ``%time,field.…`` header line, laid out after the arrays of ``value``."""
    columns: list[str] = []

    def walk(f: Field, v: Any, label: str) -> None:
        if f.is_array:
            one = element(f.base)
            for i, item in enumerate(v):
                walk(one, item, f"{label}{i}")
        elif f.base in STRUCT_CODES or f.base in ("string", "time", "duration"):
            columns.append(label)
        else:
            for f2 in codec.store.msg(f.base).fields:
                if options.keep(f2):
                    walk(f2, getattr(v, attr_name(f2.name)), f"{label}.{f2.name}")

    walk(value_type, value, "field")
    return "%time," + ",".join(columns)


class _CsvGen(GeneratedCode):
    def __init__(self, codec: Codec, options: CsvOptions) -> None:
        super().__init__({"_str": str, "_map": map})
        self.codec = codec
        self.options = options

    def emit(self, f: Field, expr: str) -> None:
        if f.is_array:
            if f.base == "bool":
                self.line(f"x(['1' if v else '0' for v in {expr}])")
            elif f.base in STRUCT_CODES:
                self.line(f"x(_map(_str, {expr}))")
            elif f.base == "string":
                self.line(f"x({expr})")
            else:
                var = self.fresh("e")
                self.line(f"for {var} in {expr}:")
                loop = len(self.lines)
                self.indent += "    "
                self.emit(element(f.base), var)
                self.indent = self.indent[:-4]
                if len(self.lines) == loop:  # every field of the element left out (--nostr)
                    self.lines.pop()
        elif f.base == "bool":
            self.line(f"a('1' if {expr} else '0')")
        elif f.base in STRUCT_CODES:
            self.line(f"a(_str({expr}))")
        elif f.base == "string":
            self.line(f"a({expr})")
        elif f.base == "time":
            self.line(f"a(_str({expr}.secs * 1000000000 + {expr}.nsecs - off))")
        elif f.base == "duration":
            self.line(f"a(_str({expr}.secs * 1000000000 + {expr}.nsecs))")
        else:
            spec = self.codec.store.msg(f.base)
            if self.codec.inline(spec.name):
                self.fields(spec.fields, expr)
                return
            for i, part in enumerate(self.codec.parts(spec)):  # as the codec does
                gen = _CsvGen(self.codec, self.options)
                gen.fields(part, "m")
                fn = gen.compile("part(m, a, x, off)", "csv", f"{spec.name} part {i}")
                self.line(f"{self.ref(fn)}({expr}, a, x, off)")

    def fields(self, fields: Sequence[Field], expr: str) -> None:
        for f in fields:
            if self.options.keep(f):
                self.emit(f, f"{expr}.{attr_name(f.name)}")


def csv_row(codec: Codec, value_type: Field, options: CsvOptions) -> Callable[[Any, int], str]:
    """``row(value, offset_ns) -> str``: the comma-joined values, time fields minus offset."""
    key = ("csv", value_type.type, value_type.is_array, options)
    fn = codec.store.cache.get(key)
    if fn is None:
        gen = _CsvGen(codec, options)
        for line in ("r = []", "a = r.append", "x = r.extend"):
            gen.line(line)
        gen.emit(value_type, "m")
        gen.line("return ','.join(r)")
        fn = codec.store.cache[key] = gen.compile("row(m, off=0)", "csv", value_type.type)
    return fn  # type: ignore[no-any-return]


def stamp_ns(value: Any) -> int | None:
    """``header.stamp`` in nanoseconds when the value is a message with a Header."""
    if getattr(value, "_has_header", False):
        stamp: Time = value.header.stamp
        return stamp.to_nsec()
    return None
