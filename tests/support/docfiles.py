"""The files the docs' examples name (``run.bag``, ``run.mcap``, ``damaged.bag``, ...).

Written with our own writers, byte for byte the same on every run, so the output an example
shows (offsets, counts, times) can be shown as it is. ``write_all(folder)`` writes them all.
"""

from __future__ import annotations

import re
import struct
import zlib
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from rostools._api.messages import message, store
from rostools.bag.formats import mcap_format as fmt
from rostools.bag.formats.access import open_writer
from rostools.bag.formats.base import BagWriter
from rostools.bag.formats.mcap_writer import McapWriter

#: The first message's time: 2023-11-14 22:13:20.123456789 UTC.
START_NS = 1_700_000_000_123_456_789
#: A drive of 12 s at 10 Hz: 6 s at 0.5 m/s, then 6 s standing.
STEPS = 120
STEP_NS = 100_000_000
CALIBRATION = b"camera_matrix: {rows: 3, cols: 3, data: [500, 0, 320, 0, 500, 240, 0, 0, 1]}\n"


def _drive(i: int) -> Iterator[tuple[str, str, dict[str, Any]]]:
    """(topic, type, values) of the messages at step ``i``."""
    speed = 0.5 if i < STEPS // 2 else 0.0
    x = 0.05 * min(i, STEPS // 2)
    stamp = {"secs": (START_NS + i * STEP_NS) // 10**9, "nsecs": (START_NS + i * STEP_NS) % 10**9}
    yield "/cmd_vel", "geometry_msgs/Twist", {"linear": {"x": speed}}
    yield (
        "/odom",
        "nav_msgs/Odometry",
        {
            "header": {"seq": i, "stamp": stamp, "frame_id": "odom"},
            "child_frame_id": "base_link",
            "pose": {"pose": {"position": {"x": x, "y": 0.0}, "orientation": {"w": 1.0}}},
            "twist": {"twist": {"linear": {"x": speed}}},
        },
    )


def write_drive(writer: BagWriter, topics: tuple[str, ...] = ("/cmd_vel", "/odom")) -> None:
    """The drive's messages on ``topics`` (renamed ``/cam`` for ``old.bag``), then close."""
    conns: dict[str, Any] = {}
    types = store()
    for i in range(STEPS):
        for topic, type_name, values in _drive(i):
            if topic not in topics:
                continue
            if topic not in conns:
                conns[topic] = writer.add_connection(
                    topic, type_name, types.md5(type_name), types.full_text(type_name),
                    callerid="/robot",
                )  # fmt: skip
            data = message(type_name, values).serialize()
            writer.write(conns[topic], START_NS + i * STEP_NS, data)


def _image_bag(path: Path) -> None:
    """``old.bag``: a camera on ``/cam``, as an older launch file named it."""
    writer = open_writer(path)
    types = store()
    image = "sensor_msgs/Image"
    conn = writer.add_connection(
        "/cam", image, types.md5(image), types.full_text(image), callerid="/camera"
    )
    for i in range(20):
        values = {"header": {"seq": i}, "height": 2, "width": 2, "encoding": "mono8", "step": 2,
                  "data": bytes([i, i, i, i])}  # fmt: skip
        writer.write(conn, START_NS + i * STEP_NS, message(image, values).serialize())
    writer.close()


def write_all(folder: Path) -> None:
    """Every file the examples name, into ``folder``."""
    folder.mkdir(parents=True, exist_ok=True)
    bag = open_writer(folder / "run.bag", chunk_size=4096)
    write_drive(bag)
    bag.close()
    # a fixed library name: the offsets the examples show do not move with the version
    mcap = McapWriter(folder / "run.mcap", library="rostools", chunk_size=4096)
    write_drive(mcap)
    crc = zlib.crc32(CALIBRATION)
    mcap.add_extra(fmt.Attachment(START_NS, START_NS, "calibration.yaml", "text/yaml",
                                  CALIBRATION, crc))  # fmt: skip
    mcap.close()
    _image_bag(folder / "old.bag")
    whole = (folder / "run.bag").read_bytes()
    # a recorder killed outright: its chunks on disk, no index
    active = open_writer(folder / "crashed.tmp", format="bag", chunk_size=4096)
    write_drive(active)
    active.flush()
    (folder / "crashed.bag.active").write_bytes((folder / "crashed.tmp").read_bytes())
    active.abort()
    # a copy cut short: its index (at the end) is gone, and part of its last chunk
    (folder / "cut.bag").write_bytes(whole[: len(whole) * 2 // 3])
    # the header of a chunk mid-file damaged, and the index (at the end) too
    damaged = bytearray(whole)
    chunks = [m.start() - 4 for m in re.finditer(b"op=\x05", whole)]
    index_pos = struct.unpack_from("<Q", whole, whole.index(b"index_pos=") + 10)[0]
    for start in (chunks[len(chunks) // 2], index_pos):
        damaged[start : start + 64] = bytes(64)
    (folder / "damaged.bag").write_bytes(bytes(damaged))
    # one bit of a message flipped inside an uncompressed chunk: the chunk's CRC fails
    flipped = McapWriter(folder / "flipped.mcap", library="rostools", compression="none",
                         chunk_size=4096)  # fmt: skip
    write_drive(flipped)
    flipped.close()
    raw = bytearray((folder / "flipped.mcap").read_bytes())
    raw[len(raw) // 3] ^= 0x01
    (folder / "flipped.mcap").write_bytes(bytes(raw))
