"""A topic's frames as rosbridge ``publish`` messages: JSON, PNG, CBOR or cbor-raw.

A frame is decoded only when a client's writer takes it (a dropped frame costs nothing), and
once for every client that takes it in the same encoding: the last one is kept per topic and
encoding. ``cbor-raw`` decodes nothing: the TCPROS bytes go out with the time they came in.
"""

from __future__ import annotations

import base64
import math
import struct
import zlib
from collections.abc import Callable
from typing import Any

from rostools.msgs import learnt
from rostools.msgs.codegen import element
from rostools.msgs.plain import to_rosbridge_json
from rostools.msgs.rosbridge import cbor_values
from rostools.msgs.store import TypeStore
from rostools.msgs.topictype import TopicType
from rostools.node.connection import Frame
from rostools.wire import cbor
from rostools.wire.rosbridge import publish_json

Encoded = str | bytes | tuple[bytes, Frame]
_NS = 1_000_000_000


class Encoders:
    """Encodes frames for rosbridge clients, each frame once per topic and encoding."""

    def __init__(self, store: TypeStore) -> None:
        self.store = store
        self._fns: dict[tuple[str, str, str], Callable[[Any], Any]] = {}
        self._last: dict[tuple[str, str], tuple[Frame, Encoded]] = {}

    def encode(
        self, topic: str, topic_type: TopicType | None, compression: str, stamp: int, frame: Frame
    ) -> Encoded:
        """``frame`` of ``topic`` as one ``publish`` message (``topic_type`` None: cbor-raw)."""
        key = (topic, compression)
        last = self._last.get(key)
        if last is not None and last[0] is frame:
            return last[1]
        out = self._encode(topic, topic_type, compression, stamp, frame)
        self._last[key] = (frame, out)
        return out

    def forget(self, topic: str) -> None:
        """Drop what is kept of ``topic`` (no client reads it now)."""
        for key in [k for k in self._last if k[0] == topic]:
            del self._last[key]

    def _encode(
        self, topic: str, topic_type: TopicType | None, compression: str, stamp: int, frame: Frame
    ) -> Encoded:
        if compression == "cbor-raw":
            # the bytes are the last item: the frame follows its head as it came, uncopied
            head = {"op": "publish", "topic": topic, "msg": {"secs": stamp // _NS,
                    "nsecs": stamp % _NS, "bytes": b""}}  # fmt: skip
            return (cbor.dumps(head)[:-1] + cbor.bytes_head(len(frame)), frame)
        if topic_type is None:
            raise ValueError(f"{topic}: its type is not known yet")
        msg = self._fn(topic_type, "decode")(frame)
        if compression == "cbor":
            values = self._fn(topic_type, "cbor")(msg)
            return cbor.dumps({"op": "publish", "topic": topic, "msg": values})
        text = publish_json(topic, self._fn(topic_type, "json")(msg))
        if compression == "png":
            return '{"op":"png","data":"' + png_text(text) + '"}'
        return text

    def _fn(self, topic_type: TopicType, kind: str) -> Callable[[Any], Any]:
        key = (topic_type.md5sum, topic_type.definition, kind)
        fn = self._fns.get(key)
        if fn is None:
            codec = learnt.codec(
                self.store, topic_type.type, topic_type.md5sum, topic_type.definition
            )
            name = topic_type.type
            if kind == "decode":
                fn = lambda data: codec.decode(name, data)  # noqa: E731
            elif kind == "cbor":
                fn = cbor_values(codec, name)
            else:
                fn = to_rosbridge_json(codec, element(name))
            self._fns[key] = fn
        return fn


def png_text(text: str) -> str:
    """``text`` in rosbridge's ``png`` compression: a PNG image's base64.

    The image is near-square, RGB, its pixels the text's UTF-8 bytes padded with newlines.
    """
    data = text.encode()
    width = max(1, math.floor(math.sqrt(len(data) / 3.0)))
    height = max(1, math.ceil(len(data) / 3.0 / width))
    data += b"\n" * (width * height * 3 - len(data))
    row = width * 3
    raw = b"".join(b"\x00" + data[y * row : (y + 1) * row] for y in range(height))

    def chunk(kind: bytes, body: bytes) -> bytes:
        return (
            struct.pack(">I", len(body)) + kind + body + struct.pack(">I", zlib.crc32(kind + body))
        )

    png = b"".join((
        b"\x89PNG\r\n\x1a\n",
        chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)),
        chunk(b"IDAT", zlib.compress(raw)),
        chunk(b"IEND", b""),
    ))  # fmt: skip
    return base64.b64encode(png).decode()
