"""Writing rosbag2: ROS 1 connections and ROS 1 message bytes in, a bag ``ros2 bag`` plays out.

A folder ``OUT/`` holds ``OUT_0.mcap`` and ``metadata.yaml`` (written on ``close``, and on
``write_metadata`` for a recorder that wants it earlier); a path ending in ``.mcap`` is the
MCAP alone. The MCAP is ``mcap_writer``'s, with profile ``ros2``: one schema per type
(encoding ``ros2msg``, the definition with the types it uses appended), one channel per
topic, type and QoS (message encoding ``cdr``, metadata ``offered_qos_profiles`` and, from
Iron on, ``topic_type_hash``), and a ``rosbag2`` metadata record holding the YAML as
rosbag2's MCAP plugin stores it.

Each message is converted as it is written (``ros2types``, ``ros2cdr``). The metadata follows
the target distro's rosbag2: version 9 from Jazzy (QoS profiles as a list of names), 8 for
Iron (a YAML string of numbers, with ``type_description_hash`` and ``ros_distro``), 5 for
Galactic and Humble, 4 before. A latched ROS 1 topic is offered ``transient_local``, the rest
``volatile``, both reliable with keep-last history of unknown depth, as ``ros2 bag record``
writes what it learns from a publisher.
"""

from __future__ import annotations

import contextlib
import os
import shutil
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

from rostools.bag.formats import mcap_format as fmt
from rostools.bag.formats.mcap_writer import DEFAULT_CHUNK_SIZE, McapWriter
from rostools.bag.formats.model import BagUsageError, Connection
from rostools.bag.formats.ros2types import DEFAULT_DISTRO, Ros2Mapping, Ros2Type
from rostools.bag.formats.sink import BIG_PAYLOAD as BIG

METADATA_FILE: Final = "metadata.yaml"
_VERSIONS: Final = {
    "dashing": 4, "eloquent": 4, "foxy": 4, "galactic": 5, "humble": 5, "iron": 8,
    "jazzy": 9, "kilted": 9, "lyrical": 9,
}  # fmt: skip
_FOREVER_OLD: Final = {"sec": 2147483647, "nsec": 4294967295}
_FOREVER: Final = {"sec": 9223372036, "nsec": 854775807}
# rmw's enums, as versions before 9 write them
_NUMBERS: Final = {"unknown": 3, "reliable": 1, "volatile": 2, "transient_local": 1}


def qos_profiles(latched: bool, version: int) -> Any:
    """``offered_qos_profiles`` as the metadata of ``version`` holds it (a list or a string)."""
    durability = "transient_local" if latched else "volatile"
    if version >= 9:
        return [
            {
                "history": "unknown", "depth": 0, "reliability": "reliable",
                "durability": durability, "deadline": dict(_FOREVER), "lifespan": dict(_FOREVER),
                "liveliness": "automatic", "liveliness_lease_duration": dict(_FOREVER),
                "avoid_ros_namespace_conventions": False,
            }
        ]  # fmt: skip
    profile = {
        "history": _NUMBERS["unknown"], "depth": 0, "reliability": _NUMBERS["reliable"],
        "durability": _NUMBERS[durability], "deadline": dict(_FOREVER_OLD),
        "lifespan": dict(_FOREVER_OLD), "liveliness": 1,
        "liveliness_lease_duration": dict(_FOREVER_OLD), "avoid_ros_namespace_conventions": False,
    }  # fmt: skip
    return _dump([profile]).strip()


@dataclass(frozen=True)
class Ros2Topic:
    """One channel of a rosbag2 being written: a topic, its ROS 2 type and its QoS.

    ``conn`` is the MCAP channel (its ``id`` the channel id); ``type.convert`` the converter.
    """

    conn: Connection
    type: Ros2Type
    latched: bool


class Rosbag2Writer:
    """A rosbag2 folder (or bare ``.mcap``) being written from ROS 1 connections and bytes.

    ``add_connection(ros1_conn)`` maps the type (``UnmappableTypeError`` naming it, before anything
    of that topic is written) and returns the ``Ros2Topic`` to write against; ``write(topic,
    t_ns, ros1_bytes)`` converts and stores one message (``ros2cdr.ConversionError`` if the
    bytes do not fit the type: nothing is stored). ``close`` finishes the MCAP and writes
    ``metadata.yaml``; leaving a ``with`` block by an exception calls ``abort``. ``stem``
    names the MCAP in a folder (``STEM_0.mcap``; the folder's name by default): a recorder
    that renames its folder when done keeps the name it will have.
    """

    def __init__(
        self,
        path: str | Path,
        *,
        distro: str = DEFAULT_DISTRO,
        mapping: Ros2Mapping | None = None,
        compression: str = "zstd",
        chunk_size: int = DEFAULT_CHUNK_SIZE,
        overwrite: bool = False,
        stem: str | None = None,
    ) -> None:
        self.mapping = mapping or Ros2Mapping(distro)
        self.distro = self.mapping.distro
        self.version = _VERSIONS[self.distro]
        self.path = Path(path)
        self.folder = self.path.suffix != ".mcap"
        if self.folder:
            if self.path.exists() and not overwrite:
                raise BagUsageError(f"{self.path} exists; refusing to overwrite it")
            if self.path.exists() and not self.path.is_dir():
                raise BagUsageError(f"{self.path} is a file, not a rosbag2 folder")
            if not self.path.parent.is_dir():
                raise BagUsageError(f"{self.path.parent}: no such folder")
            self.path.mkdir(exist_ok=True)
            self.mcap_path = self.path / f"{stem or self.path.name}_0.mcap"
        else:
            self.mcap_path = self.path
        try:
            self._mcap = McapWriter(
                self.mcap_path, compression=compression, chunk_size=chunk_size,
                overwrite=overwrite, profile="ros2",
            )  # fmt: skip
        except BaseException:
            self._remove_folder()
            raise
        self.compression = compression
        self.topics: list[Ros2Topic] = []
        self._by_key: dict[tuple[str, str, bool], Ros2Topic] = {}
        self._closed = False
        # The MCAP writer's unchecked store: every channel here is one this writer declared.
        self._store = self._mcap._store

    def add_connection(self, conn: Connection) -> Ros2Topic:
        """The channel for a ROS 1 connection, declared on first use (one per topic, type, QoS)."""
        rtype = self.mapping.map(conn)
        key = (conn.topic, rtype.name, conn.latching)
        topic = self._by_key.get(key)
        if topic is not None:
            return topic
        qos = qos_profiles(conn.latching, self.version)
        meta = {"offered_qos_profiles": qos if isinstance(qos, str) else _dump(qos).strip()}
        if self.version >= 8:
            meta["topic_type_hash"] = rtype.rihs01
        channel = self._mcap.copy_connection(
            Connection(
                id=0, topic=conn.topic, type=rtype.name, md5sum="", definition=rtype.schema,
                extra=meta, encoding="cdr", schema_encoding="ros2msg",
            )
        )  # fmt: skip
        topic = self._by_key[key] = Ros2Topic(channel, rtype, conn.latching)
        self.topics.append(topic)
        return topic

    def write(self, topic: Ros2Topic, t_ns: int, data: bytes | bytearray | memoryview) -> None:
        """Convert one ROS 1 message of ``topic`` and store it at ``t_ns``."""
        self._check_open()
        cdr = topic.type.convert(data)
        # Fresh and never changed again: a big one goes by reference (a read-only view of it)
        # rather than copied as a caller's reusable buffer would be.
        self._store(topic.conn.id, t_ns, memoryview(cdr).toreadonly() if len(cdr) >= BIG else cdr)

    def write_cdr(self, topic: Ros2Topic, t_ns: int, cdr: bytes | bytearray | memoryview) -> None:
        """Store one message already in CDR (encapsulation header first)."""
        self._check_open()
        self._store(topic.conn.id, t_ns, cdr)

    def write_stream(
        self,
        stream: Iterable[tuple[Connection, int, bytes | bytearray | memoryview]],
        on_misfit: Callable[[Connection, Exception], None],
    ) -> tuple[int, int]:
        """Convert and store ROS 1 messages ``(connection, t_ns, bytes)``: (read, written).

        The fast way in (``McapWriter.store_stream``: each message converted straight into
        the open chunk). A message whose bytes do not fit its type is left out and given to
        ``on_misfit`` with its ``ros2cdr.ConversionError``. The caller keeps the connections
        alive (they are known by identity).
        """
        from rostools.bag.formats.ros2cdr import ConversionError

        self._check_open()

        def route(conn: Connection) -> tuple[int, Any]:
            topic = self.add_connection(conn)
            return topic.conn.id, topic.type.append

        return self._mcap.store_stream(stream, route, skip=ConversionError, on_skip=on_misfit)

    def count(self, topic: Ros2Topic) -> int:
        """Messages written so far on ``topic``."""
        return self._mcap.sequence(topic.conn.id)

    @property
    def message_count(self) -> int:
        """Messages written so far."""
        return sum(self.count(t) for t in self.topics)

    def _check_open(self) -> None:
        if self._closed:
            raise BagUsageError(f"{self.path} is closed")

    def metadata(self) -> dict[str, Any]:
        """``rosbag2_bagfile_information`` as it stands (what ``metadata.yaml`` holds)."""
        start, end = self._mcap.time_span() or (0, 0)
        total = self.message_count
        duration = {"nanoseconds": end - start}
        starting = {"nanoseconds_since_epoch": start}
        name = self.mcap_path.name
        topics = []
        for t in self.topics:
            meta: dict[str, Any] = {
                "name": t.conn.topic, "type": t.type.name, "serialization_format": "cdr",
                "offered_qos_profiles": qos_profiles(t.latched, self.version),
            }  # fmt: skip
            if self.version >= 8:
                meta["type_description_hash"] = t.type.rihs01
            topics.append({"topic_metadata": meta, "message_count": self.count(t)})
        info: dict[str, Any] = {
            "version": self.version, "storage_identifier": "mcap", "duration": duration,
            "starting_time": starting, "message_count": total,
            "topics_with_message_count": topics, "compression_format": "",
            "compression_mode": "", "relative_file_paths": [name],
            "files": [{"path": name, "starting_time": starting, "duration": duration,
                       "message_count": total}],
        }  # fmt: skip
        if self.version >= 6:
            info["custom_data"] = {}
        if self.version >= 8:
            info["ros_distro"] = self.distro
        return info

    def metadata_yaml(self) -> str:
        """``metadata.yaml``'s text."""
        return _dump({"rosbag2_bagfile_information": self.metadata()})

    def write_metadata(self) -> None:
        """Write ``metadata.yaml`` now (replaced whole: a reader never sees half of one)."""
        if not self.folder:
            return
        target = self.path / METADATA_FILE
        tmp = target.with_suffix(".yaml.tmp")
        tmp.write_text(self.metadata_yaml(), encoding="utf-8")
        os.replace(tmp, target)

    def flush(self) -> None:
        """Hand every message written so far to the OS."""
        self._mcap.flush()

    def close(self) -> None:
        """Finish the MCAP (with rosbag2's metadata record) and write ``metadata.yaml``."""
        if self._closed:
            return
        inner = _dump(self.metadata())
        self._mcap.add_extra(
            fmt.Metadata("rosbag2", {"serialized_metadata": inner, "ROS_DISTRO": self.distro})
        )
        self._mcap.close()
        self._closed = True
        self.write_metadata()

    def abort(self) -> None:
        """Stop and delete what was written."""
        self._closed = True
        self._mcap.abort()
        self._remove_folder()

    def _remove_folder(self) -> None:
        if self.folder:
            with contextlib.suppress(OSError):
                (self.path / METADATA_FILE).unlink(missing_ok=True)
                if self.path.is_dir() and not any(self.path.iterdir()):
                    self.path.rmdir()

    def __enter__(self) -> Rosbag2Writer:
        return self

    def __exit__(self, exc_type: Any, exc: Any, tb: Any) -> None:
        if exc_type is None:
            self.close()
        else:
            self.abort()


def _dump(data: Any) -> str:
    """YAML as rosbag2 writes it: block style, keys in order, no anchors for shared values."""
    import yaml

    class Dumper(yaml.SafeDumper):
        def ignore_aliases(self, data: Any) -> bool:
            return True

    return yaml.dump(data, Dumper=Dumper, sort_keys=False, default_flow_style=False)


def remove_output(path: str | Path) -> None:
    """Delete a rosbag2 folder or ``.mcap`` this module wrote (an aborted conversion's)."""
    target = Path(path)
    if target.is_dir():
        shutil.rmtree(target, ignore_errors=True)
    else:
        with contextlib.suppress(FileNotFoundError):
            target.unlink()
