"""CBOR (RFC 8949) encoding of plain values, for rosbridge's ``cbor`` and ``cbor-raw``.

Only what rosbridge sends: maps with text keys, text, byte strings, integers, floats (always
8 bytes, as the ``cbor`` package rosbridge uses writes them), booleans, None, lists, and tags
(RFC 8746's typed arrays). Encoding only: the bridge reads JSON from its clients.
"""

from __future__ import annotations

import struct
from typing import Any, NamedTuple


class Tag(NamedTuple):
    """A tagged value (``tag`` 64-87: a typed array of packed little-endian numbers)."""

    tag: int
    value: Any


def _head(major: int, n: int) -> bytes:
    """The initial byte and argument of an item of ``major`` type."""
    if n < 24:
        return bytes((major << 5 | n,))
    if n < 0x100:
        return struct.pack(">BB", major << 5 | 24, n)
    if n < 0x10000:
        return struct.pack(">BH", major << 5 | 25, n)
    if n < 0x100000000:
        return struct.pack(">BI", major << 5 | 26, n)
    return struct.pack(">BQ", major << 5 | 27, n)


def _encode(value: Any, out: list[bytes]) -> None:
    if value is None:
        out.append(b"\xf6")
    elif value is True:
        out.append(b"\xf5")
    elif value is False:
        out.append(b"\xf4")
    elif isinstance(value, int):
        if not -(1 << 64) <= value < 1 << 64:
            raise ValueError(f"{value} does not fit a CBOR integer")
        out.append(_head(0, value) if value >= 0 else _head(1, -1 - value))
    elif isinstance(value, float):
        out.append(struct.pack(">Bd", 0xFB, value))
    elif isinstance(value, str):
        data = value.encode()
        out += (_head(3, len(data)), data)
    elif isinstance(value, bytes | bytearray | memoryview):
        out += (_head(2, len(value)), value if isinstance(value, bytes) else bytes(value))
    elif isinstance(value, Tag):
        out.append(_head(6, value.tag))
        _encode(value.value, out)
    elif isinstance(value, dict):
        out.append(_head(5, len(value)))
        for key, item in value.items():
            _encode(key, out)
            _encode(item, out)
    elif isinstance(value, list | tuple):
        out.append(_head(4, len(value)))
        for item in value:
            _encode(item, out)
    else:
        raise TypeError(f"CBOR cannot hold a {type(value).__name__}")


def bytes_head(length: int) -> bytes:
    """The head of a byte string of ``length`` bytes (the bytes follow it as they are)."""
    return _head(2, length)


def dumps(value: Any) -> bytes:
    """The CBOR bytes of ``value``."""
    out: list[bytes] = []
    _encode(value, out)
    return b"".join(out)
