"""A batch of messages of one layout read by numpy in one go, with no Python per message.

A type that holds only fixed-size fields and strings (``sensor_msgs/Imu``, ``nav_msgs/
Odometry``, ``sensor_msgs/NavSatFix``: most high-rate topics) has one layout per batch when
every message has the same size and each string the same length in every message (a
``frame_id`` rarely changes). Then the batch's payloads are one 2-D array of bytes: each run
of fixed fields is a column slice of it, each string a slice too, its UTF-8 checked by Arrow.
Anything else (sizes that differ, a string not UTF-8) is left to the generated per-message
decoder (``columns.py``), so the result is the same either way.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from rostools.bag.formats import runs
from rostools.bag.tables.columns import ColumnDecoder, Run, StringColumn


def fill_uniform(decoder: ColumnDecoder, parts: list[runs.Run]) -> bool:
    """Fill ``decoder``'s columns with the batch of messages ``parts`` if they share one layout.

    False (and nothing filled) when the type or the batch does not allow it.
    """
    ops = decoder.ops
    if not ops or not parts or not len(parts[0]):
        return False
    size = int(parts[0].sizes()[0])
    blocks = []
    for part in parts:
        block = part.rows(size)
        if block is None:
            return False
        blocks.append(block)
    rows = blocks[0] if len(blocks) == 1 else np.concatenate(blocks)
    pieces: list[tuple[Run | StringColumn, Any]] = []
    pos = 0
    for op, width in ops:
        if isinstance(op, Run):
            if pos + width > size:
                return False
            pieces.append((op, rows[:, pos : pos + width]))
            pos += width
            continue
        if pos + 4 > size:
            return False
        counts = rows[:, pos : pos + 4]
        if not (counts == counts[0]).all():
            return False
        length = int.from_bytes(counts[0].tobytes(), "little")
        pos += 4
        if pos + length > size:
            return False
        strings = _strings(decoder.pa, rows[:, pos : pos + length])
        if strings is None:
            return False
        pieces.append((op, strings))
        pos += length
    if pos != size:  # bytes after the message: the per-message decoder decides what they are
        return False
    for target, piece in pieces:
        if isinstance(target, Run):
            target.parts.append(piece.tobytes())
        else:
            target.built = piece
    return True


def _strings(pa: Any, cells: Any) -> Any:
    """The rows of a 2-D byte array as an Arrow string array, or None if one is not UTF-8."""
    count, width = cells.shape
    offsets = pa.py_buffer((np.arange(count + 1, dtype=np.int32) * width).tobytes())
    array = pa.StringArray.from_buffers(count, offsets, pa.py_buffer(cells.tobytes()))
    try:
        array.validate(full=True)
    except pa.ArrowInvalid:  # invalid UTF-8: the per-message path replaces it, as genpy does
        return None
    return array
