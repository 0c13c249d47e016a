"""ROS 2 messages (CDR) in MCAP files, decoded through rosbags' type system.

A rosbag2 MCAP carries each type's ``.msg`` text, with the types it uses appended after a line
of 80 ``=`` and ``MSG: pkg/msg/Type``. rosbags parses those texts and deserialises CDR; what it
cannot parse or decode is a one-line ``UnsupportedBagError`` naming the type, never a guess.
"""

from __future__ import annotations

import dataclasses
import re
from typing import Any

from rostools.bag.formats.model import Connection, UnsupportedBagError

_SECTION = re.compile(r"^={80}\n(?:MSG: )?(\S+)\n", re.M)


def _full_name(name: str) -> str:
    """``pkg/Type`` or ``pkg/msg/Type`` as rosbags names ROS 2 types (``pkg/msg/Type``)."""
    parts = name.split("/")
    return f"{parts[0]}/msg/{parts[1]}" if len(parts) == 2 else name


class Ros2Types:
    """The ROS 2 types of one file, learnt from its schemas."""

    def __init__(self) -> None:
        from rosbags.typesys import Stores, get_typestore

        self.store = get_typestore(Stores.EMPTY)
        self.known: set[str] = set()

    def learn(self, name: str, text: str) -> None:
        """Register type ``name`` and the types appended to its definition ``text``."""
        from rosbags.typesys import get_types_from_msg

        name = _full_name(name)
        if name in self.known:
            return
        pieces = _SECTION.split(text)
        sections = [(name, pieces[0])] + [
            (_full_name(pieces[i]), pieces[i + 1]) for i in range(1, len(pieces) - 1, 2)
        ]
        types: dict[str, Any] = {}
        try:
            for typename, body in sections:
                types.update(get_types_from_msg(body, typename))
            self.store.register(types)
        except Exception as err:  # noqa: BLE001 - rosbags raises several kinds; name the type
            why = (str(err).strip().splitlines() or ["unknown"])[0]
            raise UnsupportedBagError(f"cannot read the ROS 2 type {name}: {why}") from None
        self.known.add(name)

    def decode(self, name: str, data: bytes | memoryview) -> Any:
        """A CDR message as rosbags' object."""
        try:
            return self.store.deserialize_cdr(bytes(data), _full_name(name))
        except Exception as err:  # noqa: BLE001 - a short or corrupt message, as rosbags says
            why = (str(err).strip().splitlines() or ["unknown"])[0]
            raise UnsupportedBagError(f"a {name} message does not decode as CDR: {why}") from None


def plain(value: Any) -> Any:
    """A rosbags message as dicts, lists and scalars (the shape ``msgs.plain`` gives ROS 1)."""
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        # ROS 2 field names are lower case and constants upper case: keep the fields.
        return {
            f.name: plain(getattr(value, f.name))
            for f in dataclasses.fields(value)
            if f.name != "__msgtype__" and not f.name.isupper()
        }
    if hasattr(value, "tolist"):  # numpy arrays and scalars
        return value.tolist()
    if isinstance(value, list | tuple):
        return [plain(v) for v in value]
    return value


def stamp_ns(value: Any) -> int | None:
    """``header.stamp`` in ns, when the message has a ROS 2 header."""
    stamp = getattr(getattr(value, "header", None), "stamp", None)
    if stamp is None or not hasattr(stamp, "nanosec"):
        return None
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def _ros1_shape(value: Any) -> Any:
    """ROS 2 plain data in ROS 1's shape: ``{sec, nanosec}`` becomes ``{secs, nsecs}``."""
    if isinstance(value, dict):
        if value.keys() == {"sec", "nanosec"}:
            return {"secs": value["sec"], "nsecs": value["nanosec"]}
        return {k: _ros1_shape(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_ros1_shape(v) for v in value]
    return value


class ToRos1:
    """Rewrites a file's ROS 2 CDR connections and messages as their ROS 1 (Noetic) twins.

    ``pkg/msg/T`` becomes ``pkg/T`` with the definition and md5sum of the built-in store, and
    each message is filled field by field (a ROS 1 Header gets ``seq`` 0). A type the store
    does not have, or whose fields do not match, is an ``UnsupportedBagError`` naming it.
    """

    def __init__(self, cdr: set[int]) -> None:
        from rostools.msgs.codec import Codec
        from rostools.msgs.fill import Filler
        from rostools.msgs.store import TypeStore

        self.cdr = cdr
        self.types = Ros2Types()
        self.codec = Codec.of(TypeStore.default())
        self.filler = Filler(self.codec)
        self.twins: dict[int, Connection] = {}

    def connection(self, conn: Connection) -> Connection:
        """The ROS 1 connection for ``conn`` (itself when it is not CDR)."""
        if conn.id not in self.cdr:
            return conn
        twin = self.twins.get(conn.id)
        if twin is None and not conn.type:
            raise UnsupportedBagError(f"{conn.topic} holds cdr messages without a schema")
        if twin is None:
            from rostools.errors import RostoolsError

            name = conn.type.replace("/msg/", "/")
            try:
                store = self.codec.store
                twin = dataclasses.replace(
                    conn, type=name, md5sum=store.md5(name), definition=store.full_text(name),
                    extra={}, absent=frozenset(), encoding="ros1", schema_encoding="ros1msg",
                )  # fmt: skip
            except RostoolsError:
                raise UnsupportedBagError(
                    f"{conn.topic}: the ROS 2 type {conn.type} has no ROS 1 twin here "
                    "(std_msgs, geometry_msgs, sensor_msgs, nav_msgs and other Noetic types do)"
                ) from None
            self.types.learn(conn.type, conn.definition)
            self.twins[conn.id] = twin
        return twin

    def message(self, conn: Connection, data: memoryview) -> memoryview:
        """``data`` as ROS 1 bytes (unchanged when ``conn`` is not CDR)."""
        if conn.id not in self.cdr:
            return data
        from rostools.msgs.fill import FieldValueError

        twin = self.connection(conn)
        value = _ros1_shape(plain(self.types.decode(conn.type, data)))
        try:
            msg = self.filler.fill(self.codec.store.msg(twin.type), value, "")
        except FieldValueError as err:
            raise UnsupportedBagError(
                f"{conn.topic}: {conn.type} does not map onto ROS 1's {twin.type} ({err})"
            ) from None
        return memoryview(msg.serialize())


def cdr_connections(reader: Any, topics: Any = None) -> set[int]:
    """The ids of a reader's connections that carry ROS 2 CDR (none outside MCAP)."""
    from rostools.bag.formats.mcap_reader import McapReader

    if not isinstance(reader, McapReader):
        return set()
    return {
        c.id for c in reader.channels.values()
        if c.message_encoding == "cdr" and (not topics or c.topic in topics)
    }  # fmt: skip
