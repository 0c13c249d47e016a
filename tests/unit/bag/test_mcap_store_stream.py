"""``McapWriter.store_stream`` with ``ros2cdr``'s appenders: messages converted straight into
the open chunk, big runs by reference, misfits taken back out (``bag convert --to ros2``'s way).

Each stored message must be the plain converter's CDR, in order, with its sequence number, over
many chunks, and the ``mcap`` package must accept every CRC.
"""

from __future__ import annotations

import struct
from pathlib import Path
from typing import Any

import pytest

from rostools.bag.formats.mcap_writer import McapWriter
from rostools.bag.formats.model import Connection
from rostools.bag.formats.ros2cdr import ConversionError, Converters
from rostools.bag.formats.sink import BIG_PAYLOAD

#: A big byte run with a field after it: a cut, then more to convert (and fail).
TYPE = "p/msg/Blob"
DEFINITION = "uint8 a\nuint8[] data\nfloat64 tail\n"


def _converters() -> Converters:
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    store = get_typestore(Stores.EMPTY)
    store.register(get_types_from_msg(DEFINITION, TYPE))
    return Converters(lambda n: store.fielddefs[n][1], lambda n: store.fielddefs[n][1])


def _blob(size: int, tail: float, extra: bytes = b"") -> bytes:
    body = bytes((size + k) & 0xFF for k in range(size))
    return struct.pack("<BI", 7, size) + body + struct.pack("<d", tail) + extra


@pytest.mark.parametrize("compression", ["none", "zstd"])
def test_converted_into_the_chunk_as_the_converter_gives_and_misfits_left_out(
    tmp_path: Path, compression: str
) -> None:
    from mcap.reader import make_reader

    conv = _converters()
    plain, append = conv.converter(TYPE, TYPE), conv.appender(TYPE, TYPE)
    big = BIG_PAYLOAD + 3
    inputs = [
        _blob(5, 1.0),
        _blob(big, 2.0),
        _blob(big, 3.0, extra=b"x"),  # cut, then one byte too many: taken back out
        _blob(3, 4.0),
        _blob(big, 5.0)[: big // 2],  # its count says more than it holds: never cut
        _blob(big * 2, 6.0),
        _blob(0, 7.0, extra=b"yz"),
        _blob(9, 8.0),
    ]
    keys = [object(), object()]  # two connections, by identity
    stream = [(keys[i % 2], 1000 + 10 * i - (i == 3) * 25, data) for i, data in enumerate(inputs)]
    path = tmp_path / "out.mcap"
    writer = McapWriter(path, compression=compression, chunk_size=big, profile="ros2")
    ids = [
        writer.copy_connection(
            Connection(id=0, topic=f"/t{i}", type=TYPE, md5sum="", definition=DEFINITION,
                       encoding="cdr", schema_encoding="ros2msg")
        ).id
        for i in range(2)
    ]  # fmt: skip
    routed: list[Any] = []
    skipped: list[tuple[Any, str]] = []

    def route(key: object) -> tuple[int, Any]:
        routed.append(key)
        return ids[keys.index(key)], append

    read, stored = writer.store_stream(
        iter(stream[:5]), route, skip=ConversionError,
        on_skip=lambda key, err: skipped.append((key, str(err))),
    )  # fmt: skip
    assert (read, stored) == (5, 3)
    more = writer.store_stream(iter(stream[5:]), route, skip=ConversionError)
    assert more == (3, 2)
    writer.close()
    assert len(routed) == 4  # once per key and call
    assert [k for k, _ in skipped] == [keys[0], keys[0]]
    assert "1 bytes more" in skipped[0][1] and "shorter" in skipped[1][1]
    kept = [0, 1, 3, 5, 7]
    with path.open("rb") as f:
        reader = make_reader(f, validate_crcs=True)
        got = [(m.channel_id, m.log_time, m.sequence, m.data) for _, _, m in reader.iter_messages()]
        chunks = reader.get_summary().statistics.chunk_count  # type: ignore[union-attr]
    assert chunks >= 3
    seqs = {0: 0, 1: 0}
    want = []
    for i in kept:
        key = i % 2
        want.append((ids[key], stream[i][1], seqs[key], bytes(plain(inputs[i]))))
        seqs[key] += 1
    assert sorted(got, key=lambda m: (m[1], m[0])) == sorted(want, key=lambda m: (m[1], m[0]))


def test_the_appender_cuts_big_runs_only_and_keeps_the_alignment() -> None:
    conv = _converters()
    plain, append = conv.converter(TYPE, TYPE), conv.appender(TYPE, TYPE)
    cuts: list[tuple[int, int]] = []

    def cut(out: bytearray, buf: Any, start: int, end: int) -> bytearray:
        cuts.append((start, end))
        return bytearray(b"~" * 3)  # a new buffer at another offset modulo 8

    for size in (10, BIG_PAYLOAD - 1, BIG_PAYLOAD, BIG_PAYLOAD + 5):
        data = _blob(size, 9.5)
        before = len(cuts)
        out = bytearray(b"?" * 5)
        result = append(data, out, len(out) + 4, cut)
        if size < BIG_PAYLOAD:
            assert len(cuts) == before and result is out
            assert bytes(result[5:]) == bytes(plain(data))
        else:
            assert cuts[-1] == (5, 5 + size)
            whole = bytes(out[5:]) + data[5 : 5 + size] + bytes(result[3:])
            assert whole == bytes(plain(data))


def test_a_big_message_written_one_by_one_is_its_cdr(tmp_path: Path) -> None:
    """``Rosbag2Writer.write`` (``bag record --to ros2``) passes a big CDR by reference."""
    from mcap.reader import make_reader

    from rostools.bag.formats.rosbag2_writer import Rosbag2Writer
    from rostools.msgs.store import TypeStore

    store = TypeStore.default()
    conn = Connection(
        id=0, topic="/img", type="sensor_msgs/Image", md5sum=store.md5("sensor_msgs/Image"),
        definition=store.full_text("sensor_msgs/Image"),
    )  # fmt: skip
    size = BIG_PAYLOAD * 2
    head = struct.pack("<3I", 1, 2, 3) + struct.pack("<I", 3) + b"cam" + struct.pack("<II", 2, 3)
    data = head + struct.pack("<I", 4) + b"rgb8" + struct.pack("<BII", 0, 9, size)
    data += bytes(k & 0xFF for k in range(size))
    path = tmp_path / "one.mcap"
    with Rosbag2Writer(path) as writer:
        topic = writer.add_connection(conn)
        writer.write(topic, 5, data)
        with pytest.raises(ConversionError):  # short: refused, nothing stored
            writer.write(topic, 6, data[: len(data) // 2])
    with path.open("rb") as f:
        got = [m.data for _, _, m in make_reader(f, validate_crcs=True).iter_messages()]
    assert got == [bytes(topic.type.convert(data))]


def test_the_collector_runs_less_often_while_converting_and_as_before_after(
    tmp_path: Path,
) -> None:
    import gc

    from rostools.bag.tools import ros2convert
    from tests.support.ros2conv import synthetic_bag

    bag = tmp_path / "in.bag"
    synthetic_bag(bag, count=2)
    before = gc.get_threshold()
    seen: list[tuple[int, int, int]] = []
    pump = ros2convert._pump

    def spy(*args: Any) -> Any:
        seen.append(gc.get_threshold())
        if len(seen) > 1:
            raise KeyboardInterrupt  # a conversion stopped half way restores them too
        return pump(*args)

    ros2convert._pump = spy  # type: ignore[assignment]
    try:
        report = ros2convert.convert_to_ros2(bag, tmp_path / "out")
        assert report.messages_written == report.messages_read > 0
        assert gc.get_threshold() == before
        with pytest.raises(KeyboardInterrupt):
            ros2convert.convert_to_ros2(bag, tmp_path / "stopped")
        assert not (tmp_path / "stopped").exists()
    finally:
        ros2convert._pump = pump
    assert [t[0] for t in seen] == [ros2convert.GC_THRESHOLD] * 2
    assert gc.get_threshold() == before
