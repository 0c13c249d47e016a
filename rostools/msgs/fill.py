"""Messages from YAML values, with ``rostopic pub`` argument semantics.

One mapping fills fields by name and leaves the rest at their defaults; otherwise the values
fill the fields in order and must match their number. Nested messages take a mapping or a
list; times take ``now``, integer nanoseconds, float seconds, ``{secs, nsecs}`` or
``[secs, nsecs]``; a Header takes ``auto`` (stamp = now). Every value is checked here, so a
mistake names its field path and the expected type instead of failing at serialisation.
"""

from __future__ import annotations

import math
from typing import Any

from rostools.errors import UsageError
from rostools.msgs.codec import BYTE_TYPES, Codec
from rostools.msgs.codegen import attr_name
from rostools.msgs.message import Duration, Message, Time
from rostools.msgs.spec import HEADER, Field, MsgSpec

_INT_RANGES = {
    "int8": (-(1 << 7), (1 << 7) - 1), "byte": (-(1 << 7), (1 << 7) - 1),
    "uint8": (0, (1 << 8) - 1), "char": (0, (1 << 8) - 1),
    "int16": (-(1 << 15), (1 << 15) - 1), "uint16": (0, (1 << 16) - 1),
    "int32": (-(1 << 31), (1 << 31) - 1), "uint32": (0, (1 << 32) - 1),
    "int64": (-(1 << 63), (1 << 63) - 1), "uint64": (0, (1 << 64) - 1),
}  # fmt: skip


class FieldValueError(UsageError):
    """A value that does not fit its field; the message names the field path."""


def _describe(value: Any) -> str:
    text = repr(value)
    if len(text) > 40:
        text = text[:37] + "..."
    return f"{text} ({type(value).__name__})"


#: Field names a hint lists at most (a type may have 100,000 fields; the hint is one line).
HINT_NAMES = 20


def _names(spec: MsgSpec, sep: str) -> str:
    names = [f.name for f in spec.fields[:HINT_NAMES]]
    more = len(spec.fields) - len(names)
    rest = f"{sep}... ({more} more: rostools msg show {spec.name})" if more else ""
    return sep.join(names) + rest


def _fail(path: str, expected: str, value: Any, hint: str | None = None) -> FieldValueError:
    where = f"field {path}" if path else "value"
    return FieldValueError(f"{where}: expected {expected}, got {_describe(value)}", hint=hint)


class Filler:
    """Builds messages of one codec's types from YAML values."""

    def __init__(self, codec: Codec, now: Time | None = None) -> None:
        self.codec = codec
        self.now = now if now is not None else Time.now()

    def message(self, type_name: str, args: list[Any]) -> Message:
        """A message from command-line values: one mapping, or one value per field."""
        spec = self.codec.store.msg(type_name)
        if len(args) == 1 and isinstance(args[0], dict):
            return self.fill(spec, args[0], "")
        return self.fill(spec, list(args), "")

    def fill(self, spec: MsgSpec, value: Any, path: str) -> Message:
        """Fill a message of ``spec`` from a mapping, a list, or None (all defaults)."""
        msg = self.codec.message_class(spec.name)()
        if value is None:
            return msg
        if isinstance(value, dict):
            by_name = {f.name: f for f in spec.fields}
            for key, item in value.items():
                f = by_name.get(str(key))
                if f is None:
                    names = _names(spec, ", ") or "none"
                    where = f"{path}." if path else ""
                    raise FieldValueError(
                        f"no field named {where}{key} in {spec.name}", hint=f"its fields: {names}"
                    )
                setattr(msg, attr_name(f.name), self.field(f, item, _join(path, f.name)))
            return msg
        if isinstance(value, list | tuple):
            if len(value) != len(spec.fields):
                names = _names(spec, " ") or "(none)"
                raise FieldValueError(
                    f"{spec.name}{' at ' + path if path else ''} takes {len(spec.fields)} "
                    f"values in field order, got {len(value)}",
                    hint=f"expected: {names}",
                )
            for f, item in zip(spec.fields, value, strict=True):
                setattr(msg, attr_name(f.name), self.field(f, item, _join(path, f.name)))
            return msg
        raise _fail(path, f"a mapping or list for {spec.name}", value)

    def field(self, f: Field, value: Any, path: str) -> Any:
        """The Python value for one field."""
        if not f.is_array:
            return self.scalar(f.base, value, path)
        if f.base in BYTE_TYPES and isinstance(value, bytes | bytearray):
            data = bytes(value)
        elif isinstance(value, list | tuple):
            data = None
        else:
            raise _fail(path, f"a list for {f.type}", value)
        length = len(data) if data is not None else len(value)
        if f.length is not None and length != f.length:
            raise FieldValueError(f"field {path}: expected {f.length} elements, got {length}")
        if data is not None:
            return data
        items = [self.scalar(f.base, v, f"{path}[{i}]") for i, v in enumerate(value)]
        return bytes(items) if f.base in BYTE_TYPES else items

    def scalar(self, base: str, value: Any, path: str) -> Any:
        """The Python value for one element of type ``base``."""
        if base in _INT_RANGES:
            lower, upper = _INT_RANGES[base]
            if type(value) is not int:
                raise _fail(path, f"an integer ({base})", value)
            if not lower <= value <= upper:
                raise _fail(path, f"{base} in [{lower}, {upper}]", value)
            return value
        if base in ("float32", "float64"):
            if type(value) not in (int, float):
                raise _fail(path, f"a number ({base})", value)
            number = float(value)
            if base == "float32" and math.isfinite(number) and abs(number) > 3.4028234663852886e38:
                raise _fail(path, "a float32 in range", value)
            return number
        if base == "bool":
            if value not in (True, False) or type(value) not in (bool, int):
                raise _fail(path, "a bool (true/false)", value)
            return bool(value)
        if base == "string":
            if value is None:
                return ""
            if not isinstance(value, str):
                raise _fail(path, "a string", value, hint=f"quote it: '\"{value}\"'")
            return value
        if base in ("time", "duration"):
            return self.time(base, value, path)
        spec = self.codec.store.msg(base)
        if isinstance(value, str):
            if value == "auto" and base == HEADER:
                header: Any = self.codec.message_class(HEADER)()
                header.stamp = self.now
                return header
            raise _fail(path, f"a mapping or list for {base}", value)
        return self.fill(spec, value, path)

    def time(self, base: str, value: Any, path: str) -> Time | Duration:
        """A time or duration from ``now``, ns, seconds, a mapping or a pair."""
        cls = Time if base == "time" else Duration
        if value == "now" and base == "time":
            return Time(self.now.secs, self.now.nsecs)
        if type(value) is int:
            return cls.from_nsec(value)
        if type(value) is float:
            return cls.from_sec(value)
        if isinstance(value, dict) and set(value) <= {"secs", "nsecs"}:
            value = [value.get("secs", 0), value.get("nsecs", 0)]
        if (
            isinstance(value, list | tuple)
            and len(value) == 2
            and all(type(v) is int for v in value)
        ):
            result = cls(value[0], value[1])
            low = 0 if base == "time" else -(1 << 31)
            if not low <= result.secs < low + (1 << 32):
                raise _fail(path, f"a {base} that fits 32-bit seconds", value)
            return result
        expected = "now, " if base == "time" else ""
        raise _fail(
            path, f"a {base}: {expected}ns, seconds, {{secs, nsecs}} or [secs, nsecs]", value
        )


def parse_yaml_args(args: list[str]) -> list[Any]:
    """Each command-line argument parsed as YAML 1.1 (``yaml.safe_load``), as rostopic does.

    An empty argument is the empty string, as in rosservice.
    """
    from rostools import yamlio

    return ["" if arg == "" else yamlio.load(arg, f"argument {arg[:40]!r}") for arg in args]


def _join(path: str, name: str) -> str:
    return f"{path}.{name}" if path else name
