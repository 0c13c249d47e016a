"""ROS 1 bags into rosbag2 (issue 39): synthetic bags, and the oracles our output is held to.

- ``synthetic_bag``: a small .bag of random messages: every builtin type, nested and fixed
  arrays, constants, empty messages, and Noetic types whose ROS 2 twins differ (Header's
  seq, CameraInfo's D..P, Marker's and Range's added fields, tf/tfMessage's new name);
- ``rosbags_convert``: rosbags-convert's own conversion, in this process (what its CLI runs
  with ``--dst-storage mcap --dst-typestore ros2_DISTRO``);
- ``check_output``: what our rosbag2 must be: rosbags' reader reads it, every message equals
  the ROS 1 one field by field less ``seq`` (both decoded by rosbags), the MCAP passes the
  ``mcap`` package's CRC checks, and metadata.yaml has rosbag2's fields and counts.
"""

from __future__ import annotations

import contextlib
import io
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

from rostools.bag.formats.access import open_bag, open_writer
from rostools.msgs.codec import Codec
from rostools.msgs.store import Source, TypeStore, default_sources
from tests.support.randmsg import RandomMessages

SCALARS = """\
# every builtin type once, and constants of several types
int32 ANSWER=42
string GREETING=hello # this is part of the string
float64 HALF=0.5
byte LOW=-3
bool a_bool
int8 a_int8
uint8 a_uint8
byte a_byte
char a_char
int16 a_int16
uint16 a_uint16
int32 a_int32
uint32 a_uint32
int64 a_int64
uint64 a_uint64
float32 a_float32
float64 a_float64
string a_string
time a_time
duration a_duration
"""
INNER = """\
uint8 first
Scalars scalars
float64[] values
string name
std_msgs/Empty nothing
"""
ARRAYS = """\
Header header
bool[] bools
int8[3] int8s
uint8[] bytes_
uint8[5] fixed_bytes
byte[] signed_bytes
char[2] chars
int16[] int16s
uint16[3] uint16s
int32[] int32s
uint32[] uint32s
int64[2] int64s
uint64[] uint64s
float32[] float32s
float64[3] float64s
string[] strings
string[2] fixed_strings
time[] times
duration[2] durations
Scalars[] scalars
Scalars[2] fixed_scalars
Inner[] inners
std_msgs/Empty[] empties
uint8 last
"""
SYNTHETIC = {"test_ros2/Scalars": SCALARS, "test_ros2/Inner": INNER, "test_ros2/Arrays": ARRAYS}
#: Topic, type, latched: ours and Noetic's (some of whose ROS 2 twins differ).
TOPICS = [
    ("/scalars", "test_ros2/Scalars", True),
    ("/arrays", "test_ros2/Arrays", False),
    ("/inner", "test_ros2/Inner", False),
    ("/empty", "std_msgs/Empty", False),
    ("/imu", "sensor_msgs/Imu", False),
    ("/camera_info", "sensor_msgs/CameraInfo", True),
    ("/marker", "visualization_msgs/Marker", False),
    ("/range", "sensor_msgs/Range", False),
    ("/shape", "shape_msgs/SolidPrimitive", False),
    ("/tf", "tf/tfMessage", False),
    ("/status", "actionlib_msgs/GoalStatusArray", False),
]


class _Texts(Source):
    """The synthetic types' .msg texts, ahead of the built-in ones."""

    def text(self, kind: Any, name: str) -> str | None:
        return SYNTHETIC.get(name) if kind == "msg" else None

    def packages(self, kind: Any) -> Iterable[str]:
        return ["test_ros2"] if kind == "msg" else []

    def types(self, kind: Any, package: str) -> list[str]:
        return [n for n in SYNTHETIC if n.startswith(package + "/")] if kind == "msg" else []


def store() -> TypeStore:
    """The built-in Noetic types and the synthetic ones."""
    return TypeStore([_Texts(), *default_sources()])


def synthetic_bag(path: Path, count: int = 4, seed: int = 0, t0: int = 10**18) -> None:
    """A .bag of ``count`` random messages on each of ``TOPICS``, 1 ms apart."""
    types = store()
    rand = RandomMessages(Codec.of(types), seed)
    with open_writer(path) as writer:
        conns = [
            writer.add_connection(
                topic, name, types.md5(name), types.full_text(name), callerid="/gen",
                latching=latched,
            )
            for topic, name, latched in TOPICS
        ]  # fmt: skip
        t = t0
        for _ in range(count):
            for conn, (_, name, _) in zip(conns, TOPICS, strict=True):
                writer.write(conn, t, rand.message(name).serialize())
                t += 1_000_000


def rosbags_convert(
    sources: list[Path], dst: Path, distro: str, exclude: Iterable[str] = ()
) -> None:
    """What ``rosbags-convert --src ... --dst DST --dst-storage mcap --dst-typestore
    ros2_DISTRO`` writes (its function, in this process; its chatter swallowed)."""
    from rosbags.convert.converter import convert
    from rosbags.typesys import Stores, get_typestore

    with contextlib.redirect_stdout(io.StringIO()):
        convert(
            sources, dst, "mcap", 9, None, "file", None,
            get_typestore(Stores[f"ROS2_{distro.upper()}"]), list(exclude), [], [], [],
        )  # fmt: skip


def ros2_messages(folder: Path) -> dict[str, list[tuple[int, bytes]]]:
    """Every message of a rosbag2 by topic, as rosbags' reader gives them."""
    from rosbags.rosbag2 import Reader

    out: dict[str, list[tuple[int, bytes]]] = {}
    with Reader(folder) as reader:
        for conn, t, raw in reader.messages():
            out.setdefault(conn.topic, []).append((t, bytes(raw)))
    return out


def _plain(value: Any) -> Any:
    import dataclasses

    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        return {
            f.name: _plain(getattr(value, f.name))
            for f in dataclasses.fields(value)
            if not f.name.isupper() and f.name != "__msgtype__"
        }
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    return value


def same_less_seq(ros1: Any, ros2: Any, where: str = "") -> Iterator[str]:
    """Where a ROS 1 value (rosbags' plain data) and its ROS 2 twin differ, less ``seq``.

    A field ROS 2 renamed to lower case (CameraInfo's D) is found by that name; a field ROS 2
    added is not compared (it holds its default); ROS 1's byte (int8) and ROS 2's are equal
    as bytes; a ROS 1 empty message is ROS 2's one-byte placeholder.
    """
    if isinstance(ros1, list) and ros1 == ros2:
        return  # the common case, a C comparison (a point cloud's data is a million items)
    if isinstance(ros1, dict):
        if not isinstance(ros2, dict):
            yield f"{where}: {ros1!r} != {ros2!r}"
            return
        for key, value in ros1.items():
            if key == "seq" and {"stamp", "frame_id"} <= ros1.keys():
                continue
            if key == "structure_needs_at_least_one_member":
                continue
            other = key if key in ros2 else key.lower()
            if other not in ros2:
                yield f"{where}.{key}: missing in ROS 2"
                continue
            yield from same_less_seq(value, ros2[other], f"{where}.{key}")
    elif isinstance(ros1, list):
        if not isinstance(ros2, list) or len(ros1) != len(ros2):
            yield f"{where}: {ros1!r} != {ros2!r}"
            return
        for i, (a, b) in enumerate(zip(ros1, ros2, strict=True)):
            yield from same_less_seq(a, b, f"{where}[{i}]")
    elif ros1 != ros2 and not _same_byte(ros1, ros2):
        yield f"{where}: {ros1!r} != {ros2!r}"


def _same_byte(a: Any, b: Any) -> bool:
    """One byte read signed on one side and unsigned on the other (rosbags reads ROS 1's
    ``byte`` unsigned, as ROS 2 defines it; we write it ``int8``, as ROS 1 means it)."""
    return isinstance(a, int) and isinstance(b, int) and abs(a - b) == 256


#: Messages per topic decoded on both sides and compared (evenly spread; all, up to this).
PER_TOPIC = 200


def check_output(sources: list[Path], out: Path, *, exclude: Iterable[str] = ()) -> list[str]:
    """What is wrong with ``out`` (a rosbag2 folder we wrote from ``sources``); [] if nothing.

    See the module docstring for what is checked; of a long topic, ``PER_TOPIC`` messages
    spread over it are decoded and compared, the times of all.
    """
    import yaml
    from mcap.reader import make_reader
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    from rostools.bag.formats.ros2 import Ros2Types

    problems: list[str] = []
    skip = set(exclude)
    # The ROS 1 side, decoded by rosbags from each connection's definition.
    expected: dict[str, list[tuple[int, Any]]] = {}  # (time, (decode, *its arguments))
    for path in sources:
        with open_bag(path) as reader:
            stores: dict[int, Any] = {}
            for conn, t, data in reader.messages():
                if conn.topic in skip:
                    continue
                name = "/msg/".join(conn.type.split("/"))
                ts = stores.get(conn.id)
                if ts is None:
                    ts = stores[conn.id] = get_typestore(Stores.EMPTY)
                    if conn.definition.strip():
                        ts.register(get_types_from_msg(conn.definition, name))
                    else:  # an empty type (std_msgs/Empty: rosbag writes no text)
                        ts.register(get_types_from_msg("", name))
                ros1 = (ts.deserialize_ros1, bytes(data), name)
                expected.setdefault(conn.topic, []).append((t, ros1))
    # Ours, decoded by rosbags from the schemas we wrote.
    types = Ros2Types()
    got: dict[str, list[tuple[int, Any]]] = {}
    with Reader(out) as reader:
        for channel in reader.connections:
            types.learn(channel.msgtype, channel.msgdef.data)
        for channel, t, raw in reader.messages():
            ros2 = (types.decode, channel.msgtype, bytes(raw))
            got.setdefault(channel.topic, []).append((t, ros2))
        counts = {c.topic: c.msgcount for c in reader.connections}
    if sorted(got) != sorted(expected):
        problems.append(f"topics {sorted(got)} != {sorted(expected)}")
    for topic, wanted in expected.items():
        mine = sorted(got.get(topic, []), key=lambda m: m[0])
        wanted = sorted(wanted, key=lambda m: m[0])
        if [t for t, _ in mine] != [t for t, _ in wanted]:
            problems.append(f"{topic}: times differ")
            continue
        step = max(1, len(wanted) // PER_TOPIC)  # the CDR bytes are compared elsewhere
        for i, ((_, a), (_, b)) in enumerate(zip(wanted, mine, strict=True)):
            if i % step == 0:
                ros1, ros2 = _plain(a[0](a[1], a[2])), _plain(b[0](b[1], b[2]))
                problems += [f"{topic}#{i}{d}" for d in same_less_seq(ros1, ros2)][:3]
    # The MCAP, every CRC checked by the mcap package.
    mcaps = list(out.glob("*.mcap"))
    with mcaps[0].open("rb") as f:
        n = sum(1 for _ in make_reader(f, validate_crcs=True).iter_messages())
    # metadata.yaml: rosbag2's fields and the counts.
    info = yaml.safe_load((out / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    total = sum(len(v) for v in expected.values())
    fields = {
        "version", "storage_identifier", "duration", "starting_time", "message_count",
        "topics_with_message_count", "compression_format", "compression_mode",
        "relative_file_paths", "files",
    }  # fmt: skip
    if missing := fields - info.keys():
        problems.append(f"metadata.yaml lacks {sorted(missing)}")
    if n != total or info["message_count"] != total:
        problems.append(
            f"{n} messages in the MCAP, {info['message_count']} in metadata, {total} read"
        )
    if info["storage_identifier"] != "mcap" or info["relative_file_paths"] != [mcaps[0].name]:
        problems.append(
            f"storage {info['storage_identifier']}, files {info['relative_file_paths']}"
        )
    listed = {
        e["topic_metadata"]["name"]: e["message_count"] for e in info["topics_with_message_count"]
    }
    if listed != {k: v for k, v in counts.items()}:
        problems.append(f"metadata counts {listed} != reader's {counts}")
    for entry in info["topics_with_message_count"]:
        meta = entry["topic_metadata"]
        if meta["serialization_format"] != "cdr" or "offered_qos_profiles" not in meta:
            problems.append(f"{meta['name']}: {meta}")
        if info["version"] >= 8 and not str(meta.get("type_description_hash")).startswith(
            "RIHS01_"
        ):
            problems.append(f"{meta['name']}: no type_description_hash")
    return problems
