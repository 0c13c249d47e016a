"""``bag record --to ros2``: a live recording written as a rosbag2 folder, converted as it goes.

The folder is written as ``NAME.active/`` and renamed ``NAME/`` when complete, as a ``.bag``
is (``bagfile.py``); inside it, ``NAME_0.mcap`` (``rosbag2_writer``'s MCAP alone) and a
``metadata.yaml`` rewritten at each flush, so a recorder killed outright leaves a folder whose
MCAP holds all but the last second and whose metadata says what it held a second before.

A connection's type is mapped to ROS 2 once, when the connection first sends
(``Ros2Types.why_not``, on the event loop): a type that does not map is left out before any of
its frames is queued. The writer thread's mapping of the same connection then finds it done:
the mapping is shared, and only the event loop ever makes a new one.
"""

from __future__ import annotations

import os
from collections.abc import Hashable, Mapping
from pathlib import Path
from typing import TYPE_CHECKING

from rostools.bag.formats.model import BagUsageError, connection_from_header
from rostools.bag.formats.sink import Buffer
from rostools.bag.live.bagfile import BagFile, active_name

if TYPE_CHECKING:
    from rostools.bag.formats.ros2types import Ros2Mapping
    from rostools.bag.formats.rosbag2_writer import Ros2Topic


class Ros2Types:
    """The ROS 2 forms of the types a recording meets, for one distro (one ``Ros2Mapping``)."""

    def __init__(self, distro: str | None = None, rules: str | None = None) -> None:
        from rostools.bag.formats.ros2types import DEFAULT_DISTRO, Ros2Mapping

        self.mapping: Ros2Mapping = Ros2Mapping(distro or DEFAULT_DISTRO, rules)

    def why_not(self, topic: str, header: Mapping[str, str]) -> str:
        """Why a publisher's type cannot be recorded as ROS 2 ("" when it can): mapped now."""
        try:
            self.mapping.map(connection_from_header(0, topic, header))
        except Exception as err:  # noqa: BLE001 - any failure leaves its topic out, not the rest
            return (str(err).strip().splitlines() or [type(err).__name__])[0]
        return ""


class Ros2File(BagFile):
    """A rosbag2 folder being recorded as ``NAME.active/``; ``close`` completes it as ``NAME/``.

    ``BagFile``'s counts and flush clock; ``unconverted`` counts, per topic, the messages whose
    bytes did not fit their type (left out, and reported as lost).
    """

    def __init__(  # BagFile's would open a ROS 1 writer: _started is the rest of it
        self, path: Path, types: Ros2Types, compression: str | None, chunk_size: int | None
    ) -> None:
        from rostools.bag.formats.mcap_writer import DEFAULT_CHUNK_SIZE
        from rostools.bag.formats.rosbag2_writer import Rosbag2Writer

        self.path = path
        self.active = active_name(path)
        for taken in (path, self.active):
            if taken.exists():
                raise BagUsageError(f"{taken} exists; refusing to overwrite it")
        self.active.mkdir()
        self.rosbag2 = Rosbag2Writer(
            self.active / f"{path.name}_0.mcap",
            mapping=types.mapping,
            compression=compression or "zstd",
            chunk_size=chunk_size or DEFAULT_CHUNK_SIZE,
        )
        self.unconverted: dict[str, int] = {}
        self._topics: dict[Hashable, Ros2Topic] = {}
        self._started()

    def write(
        self, key: Hashable, topic: str, header: Mapping[str, str], t_ns: int, data: Buffer
    ) -> None:
        """Convert and store one raw ROS 1 message of the connection ``key``."""
        from rostools.bag.formats.ros2cdr import ConversionError

        channel = self._topics.get(key)
        if channel is None:
            conn = connection_from_header(0, topic, header)
            channel = self._topics[key] = self.rosbag2.add_connection(conn)
        try:
            self.rosbag2.write(channel, t_ns, data)
        except ConversionError:
            self.unconverted[topic] = self.unconverted.get(topic, 0) + 1
            return
        self._written(t_ns, data)

    def _flush(self) -> None:
        """The MCAP to the OS, and ``metadata.yaml`` rewritten to say what it holds."""
        self.rosbag2.flush()
        self._write_metadata()

    def _write_metadata(self) -> None:
        target = self.active / "metadata.yaml"
        tmp = target.with_name(target.name + ".tmp")
        tmp.write_text(self.rosbag2.metadata_yaml(), encoding="utf-8")
        os.replace(tmp, target)  # a reader never sees half of one

    def close(self) -> None:
        """Finish the MCAP, write the metadata and give the folder its name."""
        self.rosbag2.close()
        self._write_metadata()
        self.active.replace(self.path)
