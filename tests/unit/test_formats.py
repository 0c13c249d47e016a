"""Text, JSON and CSV output of messages, and field paths."""

from __future__ import annotations

import json
import math
import random
from typing import Any

import pytest

from rostools.errors import UsageError
from rostools.msgs import fieldpath
from rostools.msgs.codec import Codec
from rostools.msgs.codegen import attr_name
from rostools.msgs.message import Time
from rostools.msgs.plain import CsvOptions, csv_header, csv_row, dumps, to_plain
from rostools.msgs.store import BuiltinSource, TypeStore
from rostools.msgs.text import TextOptions, formatter, message_type, quote

CODEC = Codec.of(TypeStore([BuiltinSource()]))


def make(type_name: str, **kwargs: object) -> object:
    return CODEC.message_class(type_name)(**kwargs)


def text(value: object, type_name: str, **opts: object) -> str:
    return formatter(CODEC, message_type(type_name), TextOptions(**opts))(value)  # type: ignore[arg-type]


def pose() -> object:
    p = make("geometry_msgs/PoseStamped")
    p.header.seq = 7  # type: ignore[attr-defined]
    p.header.stamp = Time(12, 345)  # type: ignore[attr-defined]
    p.header.frame_id = "map"  # type: ignore[attr-defined]
    p.pose.position.x = 1.5  # type: ignore[attr-defined]
    return p


def test_echo_text_layout() -> None:
    assert text(pose(), "geometry_msgs/PoseStamped") == (
        "header: \n  seq: 7\n  stamp: \n    secs: 12\n    nsecs:       345\n"
        '  frame_id: "map"\npose: \n  position: \n    x: 1.5\n    y: 0.0\n    z: 0.0\n'
        "  orientation: \n    x: 0.0\n    y: 0.0\n    z: 0.0\n    w: 0.0"
    )


def test_arrays_strings_and_options() -> None:
    js = make("sensor_msgs/JointState", name=["a", "b c"], position=[1.0], velocity=[], effort=[])
    out = text(js, "sensor_msgs/JointState")
    assert "name: \n  - a\n  - b c\nposition: [1.0]\nvelocity: []" in out
    short = text(js, "sensor_msgs/JointState", nostr=True, noarr=True)
    assert 'name: "<array type: string, length: 2>"' in short
    assert 'frame_id: "<string length: 0>"' in short
    img = make("sensor_msgs/Image", data=bytes([1, 2, 3]), encoding="")
    assert "encoding: ''" in text(img, "sensor_msgs/Image")
    assert "data: [1, 2, 3]" in text(img, "sensor_msgs/Image")
    assert "    x: 1.50" in text(pose(), "geometry_msgs/PoseStamped", width=4)


def test_message_arrays_use_dash_items() -> None:
    ma = make("visualization_msgs/MarkerArray", markers=[make("visualization_msgs/Marker", ns="n")])
    out = text(ma, "visualization_msgs/MarkerArray")
    assert out.startswith("markers: \n  - \n    header: \n      seq: 0")
    assert '    ns: "n"' in out


@pytest.mark.parametrize(
    ("value", "quoted"),
    [("", "''"), ("map", '"map"'), ('a"b', '"a\\"b"'), ("é", '"\\xE9"'), ("a\nb", '"a\\nb"')],
)
def test_quote_like_pyyaml(value: str, quoted: str) -> None:
    assert quote(value) == quoted


def test_long_strings_fold_like_pyyaml() -> None:
    import yaml

    long = "word " * 30
    assert quote(long) == yaml.dump(long, default_style='"').rstrip("\n")


def test_json_plain_data() -> None:
    plain = to_plain(CODEC, message_type("geometry_msgs/PoseStamped"))(pose())
    assert plain["header"] == {"seq": 7, "stamp": {"secs": 12, "nsecs": 345}, "frame_id": "map"}
    nan = make("std_msgs/Float64MultiArray", data=[math.nan, math.inf, 1.0])
    line = dumps(to_plain(CODEC, message_type("std_msgs/Float64MultiArray"))(nan))
    assert json.loads(line)["data"] == ["nan", "inf", 1.0]


def test_csv_header_and_row() -> None:
    js = make("sensor_msgs/JointState", name=["a", "b"], position=[1.0, 2.0])
    vt = message_type("sensor_msgs/JointState")
    assert csv_header(CODEC, vt, js, CsvOptions()) == (
        "%time,field.header.seq,field.header.stamp,field.header.frame_id,"
        "field.name0,field.name1,field.position0,field.position1"
    )
    assert csv_row(CODEC, vt, CsvOptions())(js, 0) == "0,0,,a,b,1.0,2.0"
    assert csv_header(CODEC, vt, js, CsvOptions(nostr=True, noarr=True)) == (
        "%time,field.header.seq,field.header.stamp"
    )
    flag = make("std_msgs/Bool", data=True)
    assert csv_row(CODEC, message_type("std_msgs/Bool"), CsvOptions())(flag, 0) == "1"


def test_csv_nostr_of_an_array_of_messages_of_strings() -> None:
    """rostopic echo -p --nostr of a DiagnosticStatus with two KeyValues prints
    ``%time,field.level`` and ``1000000005,1``; the row's generated source had a ``for``
    with an empty body, and did not compile."""
    pairs = [make("diagnostic_msgs/KeyValue", key=k, value=v) for k, v in ("ab", "cd")]
    status = make("diagnostic_msgs/DiagnosticStatus", level=1, name="n", values=pairs)
    vt = message_type("diagnostic_msgs/DiagnosticStatus")
    nostr = CsvOptions(nostr=True)
    assert csv_header(CODEC, vt, status, nostr) == "%time,field.level"
    assert csv_row(CODEC, vt, nostr)(status, 0) == "1"


def test_field_paths() -> None:
    store = CODEC.store
    path = fieldpath.resolve(store, "geometry_msgs/PoseStamped", "pose/position/x")
    assert path.result.type == "float64"
    assert path.get(pose()) == 1.5
    tf = make(
        "visualization_msgs/MarkerArray",
        markers=[make("visualization_msgs/Marker", id=i) for i in range(3)],
    )
    ids = fieldpath.resolve(store, "visualization_msgs/MarkerArray", "markers[1:]/id")
    assert ids.result.is_array and ids.get(tf) == [1, 2]
    one = fieldpath.resolve(store, "visualization_msgs/MarkerArray", "markers[-1]/header")
    assert one.result.type == "std_msgs/Header"
    with pytest.raises(UsageError, match="no field named nope in geometry_msgs/Pose"):
        fieldpath.resolve(store, "geometry_msgs/PoseStamped", "pose/nope")
    with pytest.raises(UsageError, match="bad index"):
        fieldpath.resolve(store, "visualization_msgs/MarkerArray", "markers[x]")


def _fill(codec: Any, name: str, rng: random.Random) -> Any:
    """A message of type ``name`` with random field values, awkward ones included."""
    from rostools.msgs.codec import STRUCT_CODES

    texts = ["", "plain", 'q"uote', "back\\slash", "tab\tnew\nline", "ünï", "\x01\x7f", "日本"]

    def scalar(base: str) -> Any:
        if base == "bool":
            return rng.random() < 0.5
        if base in ("float32", "float64"):
            return rng.choice([0.0, -1.5, 1e300, float("nan"), float("inf"), -float("inf"), 0.1])
        if base in STRUCT_CODES:
            return rng.randrange(0, 200)
        if base == "string":
            return rng.choice(texts)
        if base in ("time", "duration"):
            return Time(rng.randrange(0, 2**31), rng.randrange(0, 10**9))
        return _fill(codec, base, rng)

    msg = codec.message_class(name)()
    for f in codec.store.msg(name).fields:
        if f.is_array:
            n = f.length if f.length is not None else rng.randrange(0, 4)
            values = [scalar(f.base) for _ in range(n)]
            value: Any = bytes(values) if f.base in ("uint8", "char") else values
        else:
            value = scalar(f.base)
        setattr(msg, attr_name(f.name), value)
    return msg


@pytest.mark.parametrize(
    "name",
    ["geometry_msgs/PoseStamped", "sensor_msgs/Image", "sensor_msgs/JointState",
     "sensor_msgs/CameraInfo", "diagnostic_msgs/DiagnosticArray", "std_msgs/Float64MultiArray",
     "sensor_msgs/PointCloud2", "std_msgs/Bool", "visualization_msgs/MarkerArray"],
)  # fmt: skip
def test_generated_json_is_dumps_of_plain(name: str) -> None:
    """``to_json`` writes byte for byte what ``dumps(to_plain(m))`` writes (cat, echo -F json)."""
    from rostools.msgs.plain import to_json

    codec = Codec.of(TypeStore.default())
    rng = random.Random(name)
    for _ in range(30):
        msg = _fill(codec, name, rng)
        value_type = message_type(name)
        assert to_json(codec, value_type)(msg) == dumps(to_plain(codec, value_type)(msg))
