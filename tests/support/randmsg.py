"""Random messages of any type, for round-trip and differential tests."""

from __future__ import annotations

import random
import string
from typing import Any

from rostools.msgs.codec import BYTE_TYPES, Codec
from rostools.msgs.codegen import attr_name
from rostools.msgs.message import Duration, Message, Time
from rostools.msgs.spec import Field

_INTS = {
    "int8": (-128, 127), "byte": (-128, 127), "uint8": (0, 255), "char": (0, 255),
    "int16": (-(2**15), 2**15 - 1), "uint16": (0, 2**16 - 1),
    "int32": (-(2**31), 2**31 - 1), "uint32": (0, 2**32 - 1),
    "int64": (-(2**63), 2**63 - 1), "uint64": (0, 2**64 - 1),
}  # fmt: skip
_TEXT = string.ascii_letters + string.digits + " _-/:.,"


class RandomMessages:
    """Builds random values; ``unicode`` adds non-ASCII and quote characters to strings."""

    def __init__(self, codec: Codec, seed: int = 0, *, unicode: bool = True) -> None:
        self.codec = codec
        self.rng = random.Random(seed)
        self.unicode = unicode

    def string(self) -> str:
        n = self.rng.choice([0, 1, 5, 12, 90])
        chars = _TEXT + ('"\\é\n\t' if self.unicode else "")
        return "".join(self.rng.choice(chars) for _ in range(n))

    def scalar(self, base: str) -> Any:
        rng = self.rng
        if base in _INTS:
            lo, hi = _INTS[base]
            return rng.choice([lo, hi, 0, rng.randint(lo, hi)])
        if base == "float32":
            import struct

            value = rng.uniform(-1e6, 1e6)
            return struct.unpack("<f", struct.pack("<f", value))[0]  # exactly representable
        if base == "float64":
            return rng.choice([0.0, -1.5, rng.uniform(-1e9, 1e9), 1e-300])
        if base == "bool":
            return rng.random() < 0.5
        if base == "string":
            return self.string()
        if base == "time":
            return Time(rng.randint(0, 2**32 - 1), rng.randint(0, 999_999_999))
        if base == "duration":
            return Duration(rng.randint(-(2**31), 2**31 - 1), rng.randint(0, 999_999_999))
        return self.message(base)

    def field(self, f: Field) -> Any:
        if not f.is_array:
            return self.scalar(f.base)
        n = f.length if f.length is not None else self.rng.choice([0, 1, 3])
        if f.base in BYTE_TYPES:
            return bytes(self.rng.randint(0, 255) for _ in range(n))
        return [self.scalar(f.base) for _ in range(n)]

    def message(self, type_name: str) -> Message:
        spec = self.codec.store.msg(type_name)
        msg = self.codec.message_class(type_name)()
        for f in spec.fields:
            setattr(msg, attr_name(f.name), self.field(f))
        return msg
