"""``tf2_msgs/TFMessage`` (and tf1's ``tf/tfMessage``, the same bytes) to and from records.

The layout is fixed, so a frame is read with ``struct`` alone: no codec, no message object.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

#: The md5sum both ``tf2_msgs/TFMessage`` and ``tf/tfMessage`` carry.
TF_MD5 = "94810edda583a504dfda3829e70d7eec"
#: The types a ``/tf`` or ``/tf_static`` publisher may declare.
TF_TYPES = ("tf2_msgs/TFMessage", "tf/tfMessage")

_U32 = struct.Struct("<I")
_STAMP = struct.Struct("<III")  # seq, secs, nsecs
_SEVEN = struct.Struct("<7d")


@dataclass(frozen=True, slots=True)
class Stamped:
    """One ``geometry_msgs/TransformStamped``: the child's pose in the parent at ``stamp_ns``.

    Frame ids are kept without a leading ``/``, as tf2's ``BufferCore`` strips it.
    """

    parent: str
    child: str
    stamp_ns: int
    translation: tuple[float, float, float]
    rotation: tuple[float, float, float, float]  # x, y, z, w


def strip_slash(frame: str) -> str:
    """``frame`` as tf2 stores it: without a leading ``/``."""
    return frame[1:] if frame.startswith("/") else frame


def _string(data: memoryview, at: int) -> tuple[str, int]:
    (n,) = _U32.unpack_from(data, at)
    at += 4
    if at + n > len(data):
        raise ValueError(f"a frame id of {n} bytes runs past the message's end")
    return bytes(data[at : at + n]).decode("utf-8", "replace"), at + n


def decode(frame: bytes | memoryview) -> list[Stamped]:
    """The transforms of one serialized ``TFMessage``.

    Raises ``ValueError`` (or ``struct.error``) when the bytes are not one.
    """
    data = memoryview(frame)
    (count,) = _U32.unpack_from(data, 0)
    # Each transform takes at least 76 bytes: a count past that cannot be real.
    if count * 76 > len(data) - 4:
        raise ValueError(f"a TFMessage of {len(data)} bytes cannot hold {count} transforms")
    at = 4
    out: list[Stamped] = []
    for _ in range(count):
        _, secs, nsecs = _STAMP.unpack_from(data, at)
        parent, at = _string(data, at + 12)
        child, at = _string(data, at)
        tx, ty, tz, qx, qy, qz, qw = _SEVEN.unpack_from(data, at)
        at += 56
        out.append(
            Stamped(
                strip_slash(parent),
                strip_slash(child),
                secs * 1_000_000_000 + nsecs,
                (tx, ty, tz),
                (qx, qy, qz, qw),
            )
        )
    return out


def encode(transforms: list[Stamped], seq: int = 0) -> bytes:
    """One serialized ``TFMessage`` holding ``transforms``, each header's seq ``seq``."""
    parts = [_U32.pack(len(transforms))]
    for t in transforms:
        secs, nsecs = divmod(t.stamp_ns, 1_000_000_000)
        parent = t.parent.encode()
        child = t.child.encode()
        parts += [
            _STAMP.pack(seq, secs, nsecs),
            _U32.pack(len(parent)),
            parent,
            _U32.pack(len(child)),
            child,
            _SEVEN.pack(*t.translation, *t.rotation),
        ]
    return b"".join(parts)
