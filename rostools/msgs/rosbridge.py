"""Messages as rosbridge v2 holds them: CBOR values out, JSON values in.

Out (``cbor_values``): rosbridge_server's ``cbor`` compression, field by field in definition
order: ``uint8[]``/``char[]`` as byte strings, other numeric arrays as RFC 8746 typed arrays
(little-endian, tags 69-86), ``bool[]`` as a list, times as ``{secs, nsecs}``. JSON out is
``plain.to_rosbridge_json``.

In (``RosbridgeFiller``): a client's ``publish``, ``call_service`` args and
``service_response`` values, as rosbridge populates a message: a mapping by field name
(fields left out keep their defaults), a list in field order, ``uint8[]`` as base64 or a
list, times as ``{secs, nsecs}``. A field that does not exist, or a value of the wrong kind,
is a ``RosbridgeValueError`` worded as rosbridge words it ("Message type std_msgs/String
does not have a field dta").
"""

from __future__ import annotations

import base64
import binascii
import math
import struct
from collections.abc import Callable
from typing import Any

from rostools.errors import UsageError
from rostools.msgs.codec import BYTE_TYPES, Codec
from rostools.msgs.codegen import attr_name
from rostools.msgs.message import Duration, Message, Time
from rostools.msgs.spec import Field, MsgSpec
from rostools.wire.cbor import Tag

#: Typed-array tags (RFC 8746) and element formats, as rosbridge's ``cbor`` writes them.
TYPED_ARRAYS = {
    "uint16": (69, "H"), "uint32": (70, "I"), "uint64": (71, "Q"),
    "byte": (72, "b"), "int8": (72, "b"), "int16": (77, "h"), "int32": (78, "i"),
    "int64": (79, "q"), "float32": (85, "f"), "float64": (86, "d"),
}  # fmt: skip
_INTS = frozenset(("byte", "char", "int8", "uint8", "int16", "uint16", "int32", "uint32",
                   "int64", "uint64"))  # fmt: skip


def cbor_values(codec: Codec, type_name: str) -> Callable[[Any], dict[str, Any]]:
    """``values(msg)``: a message of ``type_name`` as rosbridge's CBOR values."""
    spec = codec.store.msg(type_name)
    fields = [(attr_name(f.name), f.name, _cbor_field(codec, f)) for f in spec.fields]

    def values(msg: Any) -> dict[str, Any]:
        return {name: convert(getattr(msg, attr)) for attr, name, convert in fields}

    return values


def _cbor_field(codec: Codec, f: Field) -> Callable[[Any], Any]:
    base = f.base
    if not f.is_array:
        if base in ("time", "duration"):
            return lambda t: {"secs": int(t.secs), "nsecs": int(t.nsecs)}
        if base == "string":
            return str
        if base == "bool":
            return bool
        if base in _INTS:
            return int
        if base in ("float32", "float64"):
            return float
        return cbor_values(codec, base)
    if base in BYTE_TYPES:
        return bytes
    if base == "bool":
        return lambda items: [bool(i) for i in items]
    if base in TYPED_ARRAYS:
        tag, code = TYPED_ARRAYS[base]
        return lambda items: Tag(tag, struct.pack(f"<{len(items)}{code}", *items))
    item = _cbor_field(codec, Field("_", base, base, False, None))
    return lambda items: [item(i) for i in items]


class RosbridgeValueError(UsageError):
    """A client's values that do not fit the message (rosbridge's wording)."""


class RosbridgeFiller:
    """Builds messages of one codec's types from a rosbridge client's JSON values."""

    def __init__(self, codec: Codec) -> None:
        self.codec = codec

    def message(self, type_name: str, values: Any) -> Message:
        """A message of ``type_name`` from a mapping, a list in field order, or None."""
        spec = self.codec.store.msg(type_name)
        if isinstance(values, list):
            values = dict(zip((f.name for f in spec.fields), values, strict=False))
        elif not isinstance(values, dict):
            values = {}
        return self._fill(spec, values, spec.name, [])

    def _fill(self, spec: MsgSpec, values: Any, root: str, path: list[str]) -> Message:
        if not isinstance(values, dict):
            raise self._mismatch(root, path, spec.name, values)
        msg = self.codec.message_class(spec.name)()
        by_name = {f.name: f for f in spec.fields}
        for key, value in values.items():
            f = by_name.get(key)
            if f is None:
                raise RosbridgeValueError(
                    f"Message type {spec.name} does not have a field {'.'.join([*path, key])}"
                )
            setattr(msg, attr_name(f.name), self._field(f, value, root, [*path, key]))
        return msg

    def _field(self, f: Field, value: Any, root: str, path: list[str]) -> Any:
        if not f.is_array:
            return self._one(f.base, value, root, path)
        data: bytes | list[Any]
        if f.base in BYTE_TYPES and isinstance(value, str):
            try:
                data = base64.b64decode(value, validate=True)
            except binascii.Error:
                raise self._mismatch(root, path, f.type, value) from None
        elif isinstance(value, list):
            items = [self._one(f.base, v, root, path) for v in value]
            data = bytes(items) if f.base in BYTE_TYPES else items
        else:
            raise self._mismatch(root, path, f.type, value)
        if f.length is not None and len(data) != f.length:
            raise RosbridgeValueError(
                f"{root} message requires {f.length} values for field {'.'.join(path)}, "
                f"but got {len(data)}"
            )
        return data

    def _one(self, base: str, value: Any, root: str, path: list[str]) -> Any:
        if base in _INTS:
            if type(value) is int or type(value) is bool:
                return int(value)
        elif base in ("float32", "float64"):
            if type(value) in (int, float, bool):
                return float(value)
            if value is None:  # rosbridge's JSON of NaN from clients that cannot write it
                return math.nan
        elif base == "bool":
            if type(value) in (bool, int):
                return bool(value)
        elif base == "string":
            if isinstance(value, str):
                return value
        elif base in ("time", "duration"):
            if isinstance(value, dict) and set(value) <= {"secs", "nsecs"}:
                secs, nsecs = value.get("secs", 0), value.get("nsecs", 0)
                if type(secs) is int and type(nsecs) is int:
                    return (Time if base == "time" else Duration)(secs, nsecs)
        else:
            return self._fill(self.codec.store.msg(base), value, root, path)
        raise self._mismatch(root, path, base, value)

    @staticmethod
    def _mismatch(root: str, path: list[str], expected: str, value: Any) -> RosbridgeValueError:
        found = type(value)  # written "<class 'int'>", as rosbridge writes it
        if not path:
            return RosbridgeValueError(
                f"Expected a JSON object for type {root} but received a {found}"
            )
        return RosbridgeValueError(
            f"{root} message requires a {expected} for field {'.'.join(path)}, but got a {found}"
        )
