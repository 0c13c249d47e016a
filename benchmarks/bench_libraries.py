"""Why rostools has its own MCAP and .bag code and codec: the libraries beside it, one run.

Rows, each ours beside the library (``theirs``), in one process, runs interleaved:

- the ROS 1 codec: our generated decoders and encoders beside rosbags' ``deserialize_ros1``
  and ``serialize_ros1``, for a small message and a camera image (rosbags decodes arrays as
  numpy views, without a copy; ours copies them into the message);
- MCAP: our writer and reader beside the ``mcap`` package's ``Writer`` and ``make_reader``
  (small messages, zstd chunks as both write by default; 1 MB messages, uncompressed), each
  reader with chunk CRCs checked and without, and what the check costs ours; what each reads
  of a file cut mid-chunk and of one still being written, and how many of the MCAP
  conformance suite's files each reads to the messages the suite expects;
- .bag: our writer and reader beside ``rosbags.rosbag1``'s, uncompressed (its LZ4 chunks are
  ones real ROS cannot read, so they are not a fair comparison), and what each reads of a bag
  still being written (no index yet) and of one cut short.

If a library catches up, the reason for our own code is gone: these rows say when.
"""

from __future__ import annotations

import json
import os
import statistics
import struct
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from benchmarks.common import ROOT, Result

BUILD = ROOT / "benchmarks" / "build"
CORPUS = Path(os.environ.get("ROSTOOLS_CORPUS", ROOT.parent / "shared" / "corpus"))
REPEATS = 5
SMALL_COUNT = 200_000
LARGE_COUNT = 100
LARGE_SIZE = 1 << 20
STRING_MD5 = "992ce8a1687cec8c8bd883ec73ca41d1"
STRING_DEF = "string data\n"
T0 = 1_700_000_000_000_000_000


def _small(i: int) -> bytes:
    text = b"hello world %d" % i
    return struct.pack("<I", len(text)) + text


def _payloads(kind: str) -> tuple[int, list[bytes]]:
    """(count, payloads to cycle through) of a run."""
    if kind == "small":
        return SMALL_COUNT, [_small(i) for i in range(1000)]
    import numpy as np

    rng = np.random.default_rng(1)
    return LARGE_COUNT, [
        struct.pack("<I", LARGE_SIZE - 4) + rng.integers(0, 64, LARGE_SIZE - 4, np.uint8).tobytes()
        for _ in range(4)
    ]


def _stream(kind: str) -> Iterator[tuple[int, bytes]]:
    count, payloads = _payloads(kind)
    for i in range(count):
        yield T0 + i * 1_000_000, payloads[i % len(payloads)]


# -- writers and readers: each returns how many messages it handled ---------------------------


def ours_mcap_write(path: Path, kind: str, compression: str) -> int:
    from rostools.bag.formats.mcap_writer import McapWriter

    n = 0
    with McapWriter(path, compression=compression, overwrite=True) as writer:
        conn = writer.add_connection("/chatter", "std_msgs/String", STRING_MD5, STRING_DEF)
        for t, data in _stream(kind):
            writer.write(conn, t, data)
            n += 1
    return n


def mcap_package_write(path: Path, kind: str, compression: str) -> int:
    from mcap.writer import CompressionType, Writer

    n = 0
    with path.open("wb") as f:
        writer = Writer(f, compression=CompressionType[compression.upper()])
        writer.start("ros1", "bench")
        schema = writer.register_schema("std_msgs/String", "ros1msg", STRING_DEF.encode())
        channel = writer.register_channel("/chatter", "ros1", schema, {"md5sum": STRING_MD5})
        for t, data in _stream(kind):
            writer.add_message(channel, t, data, t, n)
            n += 1
        writer.finish()
    return n


def ours_read(path: Path, check_crcs: bool = True) -> int:
    from rostools.bag.formats.access import open_bag

    with open_bag(path, check_crcs=check_crcs) as reader:
        return sum(1 for _ in reader.messages())


def mcap_package_read(path: Path, validate_crcs: bool = False) -> int:
    from mcap.reader import make_reader

    with path.open("rb") as f:
        reader = make_reader(f, validate_crcs=validate_crcs)
        return sum(1 for _ in reader.iter_messages(log_time_order=True))


def ours_bag_write(path: Path, kind: str) -> int:
    from rostools.bag.formats.access import open_writer

    n = 0
    with open_writer(path, format="bag", compression="none", overwrite=True) as writer:
        conn = writer.add_connection(
            "/chatter", "std_msgs/String", STRING_MD5, STRING_DEF, callerid="/talker"
        )
        for t, data in _stream(kind):
            writer.write(conn, t, data)
            n += 1
    return n


def rosbags_write(path: Path, kind: str) -> int:
    from rosbags.rosbag1 import Writer

    path.unlink(missing_ok=True)
    n = 0
    writer = Writer(path)
    writer.open()
    conn = writer.add_connection(
        "/chatter", "std_msgs/msg/String", msgdef=STRING_DEF, md5sum=STRING_MD5, callerid="/talker"
    )
    for t, data in _stream(kind):
        writer.write(conn, t, data)
        n += 1
    writer.close()
    return n


def rosbags_read(path: Path) -> int:
    from rosbags.rosbag1 import Reader

    with Reader(path) as reader:
        return sum(1 for _ in reader.messages())


# -- timing ---------------------------------------------------------------------------------


def _rates(runs: dict[str, Callable[[], int]]) -> dict[str, float]:
    """Median messages per second of each run, the runs interleaved so drift hits all alike."""
    samples: dict[str, list[float]] = {k: [] for k in runs}
    for _ in range(REPEATS):
        for key, fn in runs.items():
            start = time.perf_counter()
            n = fn()
            samples[key].append(n / (time.perf_counter() - start))
    return {k: statistics.median(v) for k, v in samples.items()}


def _row(name: str, ours: float, theirs: float, what: str, note: str) -> Result:
    """A speed row. Writing 1 MB messages is the page cache's work for both: not slower there."""
    if "write" in name and "1 MB" in name:
        return Result(name, "msgs/s", ours, theirs, f">= 0.9x {what}", ours >= 0.9 * theirs, note)
    return Result(name, "msgs/s", ours, theirs, f"faster than {what}", ours > theirs, note)


def _label(kind: str) -> str:
    return f"{SMALL_COUNT // 1000}k small messages" if kind == "small" else f"{LARGE_COUNT} x 1 MB"


def bench_mcap_speed() -> list[Result]:
    """Write and read msgs/s: ours and the mcap package, small (zstd) and 1 MB (none)."""
    BUILD.mkdir(parents=True, exist_ok=True)
    ours_file, their_file = BUILD / "lib-ours.mcap", BUILD / "lib-theirs.mcap"
    results = []
    for kind, compression in (("small", "zstd"), ("large", "none")):
        writes = _rates(
            {
                "ours": lambda k=kind, c=compression: ours_mcap_write(ours_file, k, c),
                "theirs": lambda k=kind, c=compression: mcap_package_write(their_file, k, c),
            }
        )
        # Both read the file the mcap package wrote: neither reads its own writer's layout.
        reads = _rates(
            {
                "ours": lambda: ours_read(their_file),
                "theirs": lambda: mcap_package_read(their_file, validate_crcs=True),
                "ours unchecked": lambda: ours_read(their_file, check_crcs=False),
                "theirs unchecked": lambda: mcap_package_read(their_file),
            }
        )
        label = f"{_label(kind)}, {compression}"
        note = f"in-process, median of {REPEATS} interleaved runs; both write chunk CRCs"
        results.append(
            _row(
                f"MCAP write, {label}, vs mcap package",
                writes["ours"],
                writes["theirs"],
                "mcap Writer",
                note,
            )
        )
        note = (
            f"in-process, median of {REPEATS} interleaved runs; both read the mcap package's"
            " file in time order; ours yields views, theirs bytes"
        )
        results.append(
            _row(
                f"MCAP read, {label}, chunk CRCs checked, vs mcap package",
                reads["ours"],
                reads["theirs"],
                "mcap make_reader(validate_crcs=True)",
                note,
            )
        )
        results.append(
            _row(
                f"MCAP read, {label}, CRCs unchecked (--no-crc-check), vs mcap package",
                reads["ours unchecked"],
                reads["theirs unchecked"],
                "mcap make_reader",
                note,
            )
        )
        results.append(
            Result(
                f"MCAP read, {label}: checking CRCs, vs not (ours)",
                "msgs/s",
                reads["ours"],
                reads["ours unchecked"],
                "what the check costs: --no-crc-check skips it where that is more than a few %",
                None,
                note + "; unchecked, ours never touches the bytes of a message it yields",
            )
        )
    results += _subset_reads(their_file)
    ours_file.unlink(missing_ok=True)
    their_file.unlink(missing_ok=True)
    return results


#: Small messages on /imu for each 1 MB one on /cam, in the mixed file of ``_subset_reads``.
IMU_PER_IMAGE = 20


def _subset_reads(path: Path) -> list[Result]:
    """Reading a small topic out of a file of images: where a CRC check costs the most.

    A read of /imu alone never touches the images; a check of the chunks' CRCs passes over
    every byte of them.
    """
    from mcap.reader import make_reader
    from mcap.writer import CompressionType, Writer

    _, images = _payloads("large")
    with path.open("wb") as f:
        writer = Writer(f, compression=CompressionType.NONE)
        writer.start("ros1", "bench")
        schema = writer.register_schema("std_msgs/String", "ros1msg", STRING_DEF.encode())
        cam, imu = (
            writer.register_channel(t, "ros1", schema, {"md5sum": STRING_MD5})
            for t in ("/cam", "/imu")
        )
        for i in range(LARGE_COUNT):
            t = T0 + i * 50_000_000
            writer.add_message(cam, t, images[i % len(images)], t)
            for k in range(IMU_PER_IMAGE):
                writer.add_message(imu, t + k * 2_500_000, _small(k), t + k * 2_500_000)
        writer.finish()

    def ours(check: bool) -> int:
        from rostools.bag.formats.access import open_bag

        with open_bag(path, check_crcs=check) as reader:
            return sum(1 for _ in reader.messages(topics=["/imu"]))

    def theirs(validate: bool) -> int:
        with path.open("rb") as f:
            reader = make_reader(f, validate_crcs=validate)
            return sum(1 for _ in reader.iter_messages(topics=["/imu"], log_time_order=True))

    reads = _rates(
        {
            "ours": lambda: ours(True),
            "theirs": lambda: theirs(True),
            "ours unchecked": lambda: ours(False),
            "theirs unchecked": lambda: theirs(False),
        }
    )
    label = f"MCAP read of /imu out of {LARGE_COUNT} x 1 MB images (none)"
    note = (
        f"in-process, median of {REPEATS} interleaved runs; {IMU_PER_IMAGE} small /imu messages"
        " per image, in the mcap package's chunks"
    )
    return [
        _row(f"{label}, CRCs checked, vs mcap package", reads["ours"], reads["theirs"],
             "mcap make_reader(validate_crcs=True)", note),
        _row(f"{label}, CRCs unchecked, vs mcap package", reads["ours unchecked"],
             reads["theirs unchecked"], "mcap make_reader", note),
        Result(f"{label}: checking CRCs, vs not (ours)", "msgs/s", reads["ours"],
               reads["ours unchecked"], "what the check costs", None, note),
    ]  # fmt: skip


def bench_bag_speed() -> list[Result]:
    """Write and read msgs/s of .bag files: ours and rosbags.rosbag1, uncompressed."""
    BUILD.mkdir(parents=True, exist_ok=True)
    ours_file, their_file = BUILD / "lib-ours.bag", BUILD / "lib-theirs.bag"
    results = []
    for kind in ("small", "large"):
        writes = _rates(
            {
                "ours": lambda k=kind: ours_bag_write(ours_file, k),
                "theirs": lambda k=kind: rosbags_write(their_file, k),
            }
        )
        reads = _rates(
            {"ours": lambda: ours_read(their_file), "theirs": lambda: rosbags_read(their_file)}
        )
        note = f"in-process, median of {REPEATS} interleaved runs, uncompressed"
        results.append(
            _row(
                f".bag write, {_label(kind)}, vs rosbags.rosbag1",
                writes["ours"],
                writes["theirs"],
                "rosbags Writer",
                note,
            )
        )
        note += "; both read the file rosbags wrote"
        results.append(
            _row(
                f".bag read, {_label(kind)}, vs rosbags.rosbag1",
                reads["ours"],
                reads["theirs"],
                "rosbags Reader",
                note,
            )
        )
    ours_file.unlink(missing_ok=True)
    their_file.unlink(missing_ok=True)
    return results


# -- what each reads of damaged and unusual files ----------------------------------------


def _salvaged(read: Callable[[], Iterator[Any]]) -> int:
    """Messages a read gives before it stops (an exception ends it, as it would a user's loop)."""
    n = 0
    try:
        for _ in read():
            n += 1
    except Exception:  # noqa: BLE001 - what the library raises on a damaged file varies
        pass
    return n


def _ours_iter(path: Path) -> Iterator[Any]:
    from rostools.bag.formats.access import open_bag

    with open_bag(path) as reader:
        yield from reader.messages()


def _theirs_iter(path: Path) -> Iterator[Any]:
    from mcap.reader import make_reader

    with path.open("rb") as f:
        yield from make_reader(f).iter_messages(log_time_order=True)


def _theirs_stream(path: Path) -> Iterator[Any]:
    """The mcap package's best effort: its streaming reader, messages until it raises."""
    from mcap.records import Message
    from mcap.stream_reader import StreamReader

    with path.open("rb") as f:
        for record in StreamReader(f).records:
            if isinstance(record, Message):
                yield record


SALVAGE_COUNT = 20_000


def _salvage_files(compression: str) -> tuple[Path, Path]:
    """A file the mcap package wrote, cut in its middle chunk; and a copy taken mid-writing."""
    from mcap.writer import CompressionType, Writer

    from rostools.bag.formats.mcap_reader import McapReader

    BUILD.mkdir(parents=True, exist_ok=True)
    full, cut = BUILD / "lib-full.mcap", BUILD / f"lib-cut-{compression}.mcap"
    open_file = BUILD / f"lib-open-{compression}.mcap"
    with full.open("wb") as f:
        writer = Writer(f, compression=CompressionType[compression.upper()], chunk_size=64 * 1024)
        writer.start("ros1", "bench")
        schema = writer.register_schema("std_msgs/String", "ros1msg", STRING_DEF.encode())
        channel = writer.register_channel("/chatter", "ros1", schema, {})
        for i in range(SALVAGE_COUNT):
            writer.add_message(channel, T0 + i, _small(i), T0 + i, i)
            if i == SALVAGE_COUNT // 2:
                f.flush()
                open_file.write_bytes(full.read_bytes())  # what a reader sees mid-recording
        writer.finish()
    with McapReader(full) as reader:
        chunks = sorted(reader.chunk_indexes, key=lambda c: c.chunk_start_offset)
    middle = chunks[len(chunks) // 2]
    cut.write_bytes(full.read_bytes()[: middle.chunk_start_offset + middle.chunk_length // 2])
    full.unlink()
    return cut, open_file


def bench_mcap_salvage() -> list[Result]:
    """Messages read from a file cut mid-chunk and from one still being written.

    A chunk of small messages under 128 KiB is one zstd block, which decompresses whole or not
    at all; an lz4 frame's blocks (64 KiB) and an uncompressed chunk give what is there.
    """
    results = []
    for compression in ("lz4", "zstd"):
        cut, open_file = _salvage_files(compression)
        cases = [(f"cut mid-chunk ({compression})", cut)]
        if compression == "zstd":
            cases.append(("still being written (zstd)", open_file))
        for name, path in cases:
            ours = _salvaged(lambda p=path: _ours_iter(p))
            theirs = _salvaged(lambda p=path: _theirs_iter(p))
            streamed = _salvaged(lambda p=path: _theirs_stream(p))
            results.append(
                Result(
                    f"MCAP {name}: messages read, vs mcap package",
                    "msgs",
                    ours,
                    theirs,
                    "more than make_reader",
                    ours > theirs,
                    f"{SALVAGE_COUNT} written by the mcap package in 64 KiB chunks; theirs:"
                    f" make_reader iter_messages; its StreamReader read {streamed} before it"
                    " raised",
                )
            )
        cut.unlink()
        open_file.unlink()
    return results


def _rosbags_iter(path: Path) -> Iterator[Any]:
    from rosbags.rosbag1 import Reader

    with Reader(path) as reader:
        yield from reader.messages()


def bench_bag_salvage() -> list[Result]:
    """Messages read from a .bag still being written (no index yet) and one cut at 60%."""
    from rostools.bag.formats.access import open_writer

    BUILD.mkdir(parents=True, exist_ok=True)
    open_file, full, cut = (BUILD / f"lib-{name}.bag" for name in ("open", "full", "cut"))
    for path, close in ((open_file, False), (full, True)):
        writer = open_writer(path, format="bag", chunk_size=64 * 1024, overwrite=True)
        conn = writer.add_connection(
            "/chatter", "std_msgs/String", STRING_MD5, STRING_DEF, callerid="/talker"
        )
        for i in range(SALVAGE_COUNT):
            writer.write(conn, T0 + i, _small(i))
        if close:
            writer.close()
        else:
            writer.flush()  # what a reader sees mid-recording
            open_copy = open_file.read_bytes()
            writer.abort()
            open_file.write_bytes(open_copy)
    raw = full.read_bytes()
    cut.write_bytes(raw[: len(raw) * 6 // 10])
    results = []
    for name, path in (("still being written", open_file), ("cut at 60%", cut)):
        ours = _salvaged(lambda p=path: _ours_iter(p))
        theirs = _salvaged(lambda p=path: _rosbags_iter(p))
        results.append(
            Result(
                f".bag {name}: messages read, vs rosbags.rosbag1",
                "msgs",
                ours,
                theirs,
                "more than rosbags Reader",
                ours > theirs,
                f"{SALVAGE_COUNT} written by our writer in 64 KiB chunks",
            )
        )
    for path in (open_file, full, cut):
        path.unlink(missing_ok=True)
    return results


def _expected_messages(path: Path) -> list[tuple[int, bytes]]:
    """(log time, data) of the messages the conformance suite says a file holds."""
    records = json.loads(path.with_suffix(".json").read_text())["records"]
    out = []
    for record in records:
        if record["type"] == "Message":
            fields = dict(record["fields"])
            out.append((int(fields["log_time"]), bytes(int(b) for b in fields["data"])))
    return sorted(out)


def _reads_as_expected(
    read: Callable[[], list[tuple[int, bytes]]], expected: list[tuple[int, bytes]]
) -> bool:
    try:
        return sorted(read()) == expected
    except Exception:  # noqa: BLE001 - any failure is a file not read
        return False


def bench_mcap_conformance() -> Result | list[Result]:
    """Conformance files read to the messages the suite expects: ours and the mcap package."""
    from mcap.reader import make_reader

    from rostools.bag.formats.mcap_reader import McapReader

    files = sorted((CORPUS / "mcap" / "conformance").rglob("*.mcap"))
    if not files:
        print(f"bench_mcap_conformance: no conformance files under {CORPUS}; skipped")
        return []

    def ours(path: Path) -> list[tuple[int, bytes]]:
        with McapReader(path) as reader:
            return [(t, bytes(d)) for _, t, d in reader.messages()]

    def theirs(path: Path) -> list[tuple[int, bytes]]:
        with path.open("rb") as f:
            return [(m.log_time, m.data) for _, _, m in make_reader(f).iter_messages()]

    ok_ours = ok_theirs = 0
    for path in files:
        expected = _expected_messages(path)
        ok_ours += _reads_as_expected(lambda p=path: ours(p), expected)
        ok_theirs += _reads_as_expected(lambda p=path: theirs(p), expected)
    return Result(
        f"MCAP conformance files read to the expected messages (of {len(files)})",
        "files",
        ok_ours,
        ok_theirs,
        "all of them",
        ok_ours == len(files),
        "theirs: mcap make_reader iter_messages; the suite's JSON lists each file's messages",
    )


#: (type, a message of it) for the codec rows: a small one and a camera image.
CODEC_CASES = ("geometry_msgs/PoseStamped", "sensor_msgs/Image")


def _codec_message(codec: Any, type_name: str) -> Any:
    """A filled message: a pose in a frame, or a 640 x 480 rgb8 image."""
    msg = codec.message_class(type_name)()
    msg.header.frame_id = "map"
    if type_name.endswith("Image"):
        msg.height, msg.width, msg.encoding, msg.step = 480, 640, "rgb8", 1920
        msg.data = bytes(range(256)) * (480 * 1920 // 256)
    else:
        msg.pose.position.x = 1.5
        msg.pose.orientation.w = 1.0
    return msg


def _codec_runs(
    count: int, ours: tuple[Any, bytes, Any], theirs: tuple[Any, str, Any]
) -> dict[str, Callable[[], int]]:
    """``count`` decodes and encodes, each way: our decoder, wire bytes and message; rosbags'
    store, type name and message."""
    decode, wire, message = ours
    store, name, their_message = theirs

    def ours_decode() -> int:
        for _ in range(count):
            decode(wire, 0)
        return count

    def theirs_decode() -> int:
        for _ in range(count):
            store.deserialize_ros1(wire, name)
        return count

    def ours_encode() -> int:
        for _ in range(count):
            message.serialize()
        return count

    def theirs_encode() -> int:
        for _ in range(count):
            store.serialize_ros1(their_message, name)
        return count

    return {
        "ours decode": ours_decode,
        "theirs decode": theirs_decode,
        "ours encode": ours_encode,
        "theirs encode": theirs_encode,
    }


def bench_codec_speed() -> list[Result]:
    """Decode and encode msgs/s: our generated codec beside rosbags' ROS 1 serde."""
    from rosbags.typesys import Stores, get_typestore

    from rostools.msgs.codec import Codec
    from rostools.msgs.store import BuiltinSource, TypeStore

    codec = Codec.of(TypeStore([BuiltinSource()]))
    store = get_typestore(Stores.ROS1_NOETIC)
    results = []
    for type_name in CODEC_CASES:
        theirs_name = type_name.replace("/", "/msg/")
        wire = _codec_message(codec, type_name).serialize()
        decode = codec.decoder(type_name)
        message = decode(wire, 0)[0]
        theirs_message = store.deserialize_ros1(wire, theirs_name)
        assert store.serialize_ros1(theirs_message, theirs_name) == wire  # the same bytes
        count = 20_000 if type_name.endswith("Stamped") else 200
        runs = _codec_runs(count, (decode, wire, message), (store, theirs_name, theirs_message))
        note = f"in-process, median of {REPEATS} interleaved runs; the same bytes both ways"
        for what in ("decode", "encode"):
            rates = _rates({"ours": runs[f"ours {what}"], "theirs": runs[f"theirs {what}"]})
            results.append(
                Result(
                    f"ROS 1 {what}, {type_name}, vs rosbags",
                    "msgs/s",
                    rates["ours"],
                    rates["theirs"],
                    "faster than rosbags",
                    rates["ours"] > rates["theirs"],
                    note,
                )
            )
    return results


BENCHMARKS = {
    "lib_codec_speed": bench_codec_speed,
    "lib_mcap_speed": bench_mcap_speed,
    "lib_mcap_salvage": bench_mcap_salvage,
    "lib_mcap_conformance": bench_mcap_conformance,
    "lib_bag_speed": bench_bag_speed,
    "lib_bag_salvage": bench_bag_salvage,
}
