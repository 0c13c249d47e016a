"""The sampling layer of ``topic plot`` and ``bag plot``: partial decoders, samplers, series."""

from __future__ import annotations

import random
import struct
from typing import Any

import pytest

from rostools.errors import UsageError
from rostools.msgs import extract, fieldpath
from rostools.msgs.codec import Codec, DecodeError
from rostools.msgs.codegen import attr_name
from rostools.msgs.expr import compile_expression
from rostools.msgs.message import Message, Time
from rostools.msgs.sample import MAX_SLICE, Labels, Sampler
from rostools.msgs.spec import Field
from rostools.msgs.store import TypeStore
from rostools.series import Series, SeriesSet, columns
from tests.support.randmsg import RandomMessages


@pytest.fixture(scope="module")
def codec() -> Codec:
    return Codec.of(TypeStore.default())


def _number(value: Any) -> Any:
    if isinstance(value, list):
        return [_number(v) for v in value]
    if hasattr(value, "to_sec"):
        return value.to_sec()
    return value + 0 if isinstance(value, bool) else value


def _paths(codec: Codec, msg: Message, rng: random.Random, prefix: str = "") -> list[str]:
    """Paths to numbers in ``msg``: every scalar, and indices and slices into its arrays."""
    found: list[str] = []
    for f in codec.store.msg(msg._type).fields:
        value = getattr(msg, attr_name(f.name))
        name = prefix + f.name
        element = Field(f.name, f.base, f.base, False, None)
        numeric = f.base in extract.NUMERIC_TYPES
        if not f.is_array:
            if numeric:
                found.append(name)
            elif f.base != "string":
                found += _paths(codec, value, rng, name + "/")
            continue
        n = len(value)
        if numeric:
            found += [f"{name}[1:]", f"{name}[::-2]", f"{name}[-2:]"]
        if n:
            i = rng.randrange(-n, n)
            if numeric:
                found.append(f"{name}[{i}]")
            elif element.base != "string":
                found += _paths(codec, value[i], rng, f"{name}[{i}]/")
                inner = _paths(codec, value[0], rng, "")
                found += [f"{name}[0:2]/{p}" for p in inner if "[" not in p][:2]
    return found


def test_extractors_read_what_the_full_decoder_reads(codec: Codec) -> None:
    """Every numeric path into random messages of every built-in type: the partial
    decoder's number is the decoded message's, element for element."""
    rng = random.Random(3)
    checked = 0
    types = [t for t in codec.store.types("msg") if not t.startswith(("rosgraph_msgs/Log",))]
    for type_name in types:
        gen = RandomMessages(codec, seed=rng.randrange(1 << 30))
        for _ in range(2):
            msg = gen.message(type_name)
            data = codec.serialize(msg)
            decoded = codec.decode(type_name, data)
            for text in _paths(codec, decoded, rng):
                path = fieldpath.resolve(codec.store, type_name, text)
                fn = extract.extractor(codec, type_name, path)
                assert fn(data) == _number(path.get(decoded)), (type_name, text)
                assert fn(memoryview(data)) == fn(data)
                checked += 1
    assert checked > 2000


def test_extractor_errors(codec: Codec) -> None:
    odom = "nav_msgs/Odometry"
    with pytest.raises(UsageError, match="not a number"):
        extract.extractor(codec, odom, fieldpath.resolve(codec.store, odom, "header/frame_id"))
    with pytest.raises(UsageError, match=r"float64\[36\], not a number") as err:
        extract.extractor(codec, odom, fieldpath.resolve(codec.store, odom, "pose/covariance"))
    assert "slice an array" in str(err.value.hint)
    scan = "sensor_msgs/LaserScan"
    fn = extract.extractor(codec, scan, fieldpath.resolve(codec.store, scan, "ranges[3]"))
    msg = codec.message_class(scan)(ranges=[1.0, 2.0])
    with pytest.raises(IndexError):
        fn(codec.serialize(msg))
    data = codec.serialize(codec.message_class(scan)(ranges=[1.0] * 5))
    with pytest.raises(struct.error):
        fn(data[:-16])  # the last two ranges cut off
    # Only what the path needs is read: a count that lies is caught where it is skipped over
    lying = bytearray(data)
    struct.pack_into("<I", lying, len(data) - 4 * 5 - 4 - 4, 1 << 30)  # ranges' count
    after = fieldpath.resolve(codec.store, scan, "intensities[0]")
    with pytest.raises(struct.error):
        extract.extractor(codec, scan, after)(bytes(lying))
    kind = "visualization_msgs/MarkerArray"
    markers = codec.message_class(kind)(
        markers=[codec.message_class("visualization_msgs/Marker")()]
    )
    lying = bytearray(codec.serialize(markers))
    struct.pack_into("<I", lying, 0, 1 << 30)
    last = extract.extractor(codec, kind, fieldpath.resolve(codec.store, kind, "markers[-1]/id"))
    with pytest.raises(struct.error):
        last(bytes(lying))  # refused before any loop over 2**30 elements


def test_skips_arrays_of_variable_messages(codec: Codec) -> None:
    """A field after an array of messages with strings inside is found by walking them."""
    kind = "visualization_msgs/MarkerArray"
    cls = codec.message_class
    markers = [cls("visualization_msgs/Marker")(ns="n" * k, id=k) for k in range(4)]
    markers[2].pose.position.x = 2.5
    data = codec.serialize(cls(kind)(markers=markers))
    for text, want in [
        ("markers[2]/pose/position/x", 2.5),
        ("markers[-1]/id", 3),
        ("markers[1:3]/id", [1, 2]),
        ("markers[::2]/pose/position/x", [0.0, 2.5]),
    ]:
        fn = extract.extractor(codec, kind, fieldpath.resolve(codec.store, kind, text))
        assert fn(data) == want, text


def _odom(codec: Codec, x: float, stamp: float, frame: str = "odom") -> bytes:
    msg = codec.message_class("nav_msgs/Odometry")()
    msg.header.stamp = Time.from_sec(stamp)
    msg.header.frame_id = frame
    msg.pose.pose.position.x = x
    msg.pose.covariance = [float(i) for i in range(36)]
    return codec.serialize(msg)


def test_sampler_labels_x_and_filter(codec: Codec) -> None:
    got: list[tuple[str, float, float]] = []

    def sink(label: str) -> Any:
        return lambda x, y: got.append((label, x, y))

    frames = [_odom(codec, 1.5, 100.25), _odom(codec, -2.0, 101.5, "x" * 40)]
    odom = "nav_msgs/Odometry"
    plain = Sampler(codec.store, odom, "/odom", ["pose/pose/position/x"], sink)
    assert plain.feed(frames, 7.0) == 2
    assert got == [
        ("/odom/pose/pose/position/x", 7.0, 1.5),
        ("/odom/pose/pose/position/x", 7.0, -2.0),
    ]
    got.clear()
    keep = compile_expression("m.pose.pose.position.x < 0")
    paths = ["pose/covariance[0:3]", "/twist/twist/linear/z"]
    stamped = Sampler(codec.store, odom, "/odom", paths, sink, stamp=True, keep=keep)
    assert stamped.feed(frames, 7.0) == 1
    assert got == [
        ("/odom/pose/covariance[0]", 101.5, 0.0),
        ("/odom/pose/covariance[1]", 101.5, 1.0),
        ("/odom/pose/covariance[2]", 101.5, 2.0),
        ("/odom/twist/twist/linear/z", 101.5, 0.0),
    ]
    got.clear()
    neg = Sampler(codec.store, odom, "/odom", ["pose/covariance[-2:]"], sink)
    neg.feed(frames[:1], 1.0)
    assert [g[0] for g in got] == ["/odom/pose/covariance[-2:][0]", "/odom/pose/covariance[-2:][1]"]
    assert [g[2] for g in got] == [34.0, 35.0]
    assert Labels("/scan", "ranges[2:8:3]").known() == ["/scan/ranges[2]", "/scan/ranges[5]"]
    assert Labels("/scan", "ranges[2:]").known() == []  # its length comes with each message
    with pytest.raises(UsageError, match="one slice per field path"):
        Labels("/a", "b[0:2]/c[0:2]")


def test_sampler_refusals(codec: Codec) -> None:
    def sink(label: str) -> Any:
        return lambda x, y: None

    with pytest.raises(UsageError, match="give a field") as err:
        Sampler(codec.store, "nav_msgs/Odometry", "/odom", [""], sink)
    assert err.value.hint == "for example /odom/pose/pose/position/x"
    with pytest.raises(UsageError, match="no header"):
        Sampler(codec.store, "geometry_msgs/Twist", "/cmd_vel", ["linear/x"], sink, stamp=True)
    with pytest.raises(UsageError, match="no field named z in float64"):
        Sampler(codec.store, "geometry_msgs/Twist", "/cmd_vel", ["linear/y/z"], sink)
    with pytest.raises(UsageError, match=f"more than {MAX_SLICE}"):
        Sampler(codec.store, "sensor_msgs/LaserScan", "/scan", ["ranges[0:100]"], sink)
    scan = Sampler(codec.store, "sensor_msgs/LaserScan", "/scan", ["ranges[5]"], sink)
    short = codec.serialize(codec.message_class("sensor_msgs/LaserScan")(ranges=[1.0]))
    assert scan.feed([short], 0.0) == 1
    assert scan.missed == 1
    with pytest.raises(DecodeError, match="on /scan does not decode as sensor_msgs/LaserScan"):
        scan.feed([short[:10]], 0.0)


def test_series_window_thinning_and_columns() -> None:
    plot = SeriesSet(window=10.0, max_points=1200)
    for i in range(3000):
        plot.add("a", i * 0.01, float(i % 7))
    plot.add("a", 29.0, float("nan"))  # not kept
    plot.trim()
    a = plot.series["a"]
    assert a.xs[0] >= plot.newest - 10.0 and a.xs[-1] == pytest.approx(29.99)
    assert len(a) <= 1201 and not a.thinned  # the window, not thinning, bounds it
    whole = SeriesSet(max_points=1000)
    assert whole.newest == float("-inf")
    for i in range(5000):
        whole.add("b", float(i), 1000.0 if i == 123 else float(i % 10))
    b = whole.series["b"]
    assert b.thinned and len(b) <= 1000
    assert max(b.ys) == 1000.0 and min(b.ys) == 0.0  # the spike and the floor survive thinning
    assert list(b.xs) == sorted(b.xs)
    xs, ys = columns(b, 0.0, 4999.0, 50)
    assert len(xs) <= 100 and max(ys) == 1000.0 and xs == sorted(xs)
    few = Series()
    few.xs.extend([1.0, 2.0])
    few.ys.extend([3.0, 4.0])
    assert columns(few, 0.0, 10.0, 80) == ([1.0, 2.0], [3.0, 4.0])
    assert whole.bounds() == (0.0, 4999.0) and SeriesSet().bounds() is None


def test_only_the_plot_commands_import_the_plot_libraries() -> None:
    """plotext and matplotlib load when a plot is drawn, not with the groups that hold it."""
    import subprocess
    import sys

    code = (
        "import sys\n"
        "import rostools.cli.topic, rostools.cli.bag, rostools.cli.node, rostools.cli.app\n"
        "print(sorted(m for m in ('plotext', 'matplotlib') if m in sys.modules))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]"


def test_n_is_exact_across_topics() -> None:
    """Once -n messages are in, another topic's read that was already on its way is not sampled
    (``topic plot -n 60`` of two topics sampled 61 now and then)."""
    from types import SimpleNamespace

    from rostools.cli.topic.plot import _Live

    store = TypeStore.default()
    live = _Live(["/a/data", "/b/data"], store, SeriesSet(10.0), False, None, 2)
    live.paths = {"/a": ["data"], "/b": ["data"]}
    header = {"type": "std_msgs/Float64", "md5sum": store.md5("std_msgs/Float64")}
    conn: Any = SimpleNamespace(header=header)
    one = struct.pack("<d", 1.0)
    assert live.on_frames("/a", [one, one], conn, 0.0) is False and live.done
    assert live.on_frames("/b", [one], conn, 0.0) is False
    assert live.received == 2 and "/b/data" not in live.plot.series
