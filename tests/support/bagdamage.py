"""Damage that aims at a bag's structure, and what a reader must still give back.

Each mutation damages one part of a ``.bag`` or MCAP file (a chunk's header, a record inside
an uncompressed chunk, an index record, the chunk infos, two chunks swapped ...) and says
which messages are intact: those the reader must return. The fuzz suite (test_fuzz_bags) and
the unit tests use them.
"""

from __future__ import annotations

import hashlib
import struct
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

from rostools.bag.formats import mcap_format, rosbag1_format as fmt
from rostools.bag.formats.access import open_bag
from rostools.bag.formats.mcap_reader import McapReader
from rostools.bag.formats.rosbag1_reader import Bag1Reader
from tests.support.bagdata import bag_records, chunk_spans, swap_spans

#: A message as the checks compare them: topic, time (ns), md5 of the bytes.
Message = tuple[str, int, str]


def messages_of(
    path: Path, topics: list[str] | None = None
) -> tuple[list[Message], Bag1Reader | McapReader]:
    """What our reader gives from ``path`` (of ``topics``), and the reader (closed)."""
    reader = open_bag(path)
    assert isinstance(reader, Bag1Reader | McapReader)
    with reader:
        got = [(c.topic, t, _md5(d)) for c, t, d in reader.messages(topics=topics)]
    return got, reader


@dataclass
class Source:
    """An intact file and where its parts are."""

    name: str
    raw: bytes
    messages: list[Message]
    #: (start, end) of each chunk: the chunk and its index records (.bag) or its record and
    #: the message indexes after it (MCAP); the messages of each; whether it is compressed.
    chunks: list[tuple[int, int]] = field(default_factory=list)
    chunk_messages: list[list[Message]] = field(default_factory=list)
    compressed: list[bool] = field(default_factory=list)
    #: .bag: inner message records of uncompressed chunks, as (start, data start, message).
    inner: list[tuple[int, int, Message]] = field(default_factory=list)

    @property
    def mcap(self) -> bool:
        return self.raw.startswith(mcap_format.MAGIC)


def load(name: str, path: Path) -> Source:
    """Read an intact file's layout and messages (chunks must not overlap in time)."""
    raw = path.read_bytes()
    messages, _ = messages_of(path)
    source = Source(name, raw, messages)
    if source.mcap:
        _mcap_layout(source, path)
    else:
        _bag_layout(source, path)
    return source


def _bag_layout(source: Source, path: Path) -> None:
    raw = source.raw
    source.chunks = chunk_spans(raw)
    reader = Bag1Reader(path)
    with reader:
        wanted = reader.wanted(None, None)
        topics = {c.id: c.topic for c in reader.connections}
        for chunk in reader.chunks:
            source.chunk_messages.append(
                [(c.topic, t, _md5(d)) for c, t, d in reader.chunk_messages(chunk, wanted)]
            )
            source.compressed.append(chunk.compression != "none")
            if chunk.compression != "none":
                continue
            end = chunk.data_pos + chunk.data_len
            for pos, op, fields, data, dlen in bag_records(raw, chunk.data_pos, end):
                if op == fmt.OP_MSG_DATA:
                    topic = topics[fmt.u32_field(fields, "conn")]
                    message = (topic, fmt.time_field(fields, "time"), _md5(raw[data : data + dlen]))
                    source.inner.append((pos, data, message))


def _md5(data: bytes | memoryview) -> str:
    return hashlib.md5(data).hexdigest()


def _mcap_layout(source: Source, path: Path) -> None:
    reader = McapReader(path)
    with reader:
        indexes = sorted(reader.chunk_indexes, key=lambda i: i.chunk_start_offset)
        ends = [i.chunk_start_offset for i in indexes[1:]]
        data_end = reader._data_end
    for index, end in zip(indexes, [*ends, None], strict=True):
        start = index.chunk_start_offset
        if end is None:  # the last chunk runs to its message indexes' end
            end = start + index.chunk_length + index.message_index_length
        source.chunks.append((start, end))
        lo, hi = index.message_start_time, index.message_end_time
        source.chunk_messages.append([m for m in source.messages if lo <= m[1] <= hi])
        source.compressed.append(index.compression != "")
    assert source.chunks[-1][1] <= data_end


#: The mutations of each format (``mutate``); ``bag doctor`` must flag every one.
BAG_KINDS = (
    "chunk_header", "message_header", "index_header", "connection_header", "chunk_info",
    "swap", "flip_index",
)  # fmt: skip
MCAP_KINDS = ("chunk_header", "swap", "chunk_times", "message_index")


@dataclass
class Mutant:
    """A damaged copy, and the messages a reader must still give."""

    what: str
    raw: bytes
    intact: list[Message]


def mutate(source: Source, kind: str, pick: int, bit: int) -> Mutant | None:
    """Damage ``source`` as ``kind`` says, at the part ``pick`` chooses; None if it has none."""
    if source.mcap:
        return _mutate_mcap(source, kind, pick, bit)
    return _mutate_bag(source, kind, pick, bit)


def _zero(raw: bytes, start: int, end: int) -> bytes:
    return raw[:start] + bytes(end - start) + raw[end:]


def _without(messages: list[Message], lost: list[Message]) -> list[Message]:
    """``messages`` less one of each in ``lost``."""
    left = Counter(lost)
    out = []
    for m in messages:
        if left[m]:
            left[m] -= 1
        else:
            out.append(m)
    return out


def _mutate_bag(source: Source, kind: str, pick: int, bit: int) -> Mutant | None:
    raw, everything = source.raw, source.messages
    records = bag_records(raw)
    if kind == "chunk_header":
        i = pick % len(source.chunks)
        chunk = next(r for r in records if r[0] == source.chunks[i][0])
        lost = source.chunk_messages[i] if source.compressed[i] else []
        return Mutant(f"chunk {i} header zeroed", _zero(raw, chunk[0], chunk[3]),
                      _without(everything, lost))  # fmt: skip
    if kind == "message_header":
        if not source.inner:
            return None
        pos, data, message = source.inner[pick % len(source.inner)]
        return Mutant(f"message record at {pos} zeroed", _zero(raw, pos, data),
                      _without(everything, [message]))  # fmt: skip
    ops = {"index_header": fmt.OP_INDEX_DATA, "connection_header": fmt.OP_CONNECTION,
           "chunk_info": fmt.OP_CHUNK_INFO, "flip_index": fmt.OP_INDEX_DATA}  # fmt: skip
    if kind in ops:
        index_start = source.chunks[-1][1]
        found = [r for r in records if r[1] == ops[kind] and (kind != "connection_header"
                                                               or r[0] >= index_start)]  # fmt: skip
        pos, _, _, data, dlen = found[pick % len(found)]
        if kind in ("index_header", "connection_header"):
            return Mutant(f"{kind} at {pos} zeroed", _zero(raw, pos, data), everything)
        if kind == "flip_index":  # one bit of an entry: a time or an offset
            at = data + (pick // len(found)) % max(dlen, 1)
        else:  # one bit of a chunk info's times or counts
            places = [data + k for k in range(dlen)]
            header = raw[pos:data]
            for name in (b"start_time=", b"end_time="):
                k = header.index(name) + len(name)
                places += [pos + k + j for j in range(8)]
            at = places[(pick // len(found)) % len(places)]
        damaged = bytearray(raw)
        damaged[at] ^= 1 << (bit % 8)
        return Mutant(f"{kind}: bit {bit % 8} of byte {at} flipped", bytes(damaged), everything)
    if kind == "swap":
        if len(source.chunks) < 2:
            return None
        i = pick % len(source.chunks)
        j = (i + 1 + (pick // len(source.chunks)) % (len(source.chunks) - 1)) % len(source.chunks)
        i, j = sorted((i, j))
        return Mutant(f"chunks {i} and {j} swapped",
                      swap_spans(raw, source.chunks[i], source.chunks[j]), everything)  # fmt: skip
    raise AssertionError(kind)


def _mutate_mcap(source: Source, kind: str, pick: int, bit: int) -> Mutant | None:
    raw, everything = source.raw, source.messages
    if not source.chunks:
        return None
    i = pick % len(source.chunks)
    start, end = source.chunks[i]
    if kind == "chunk_header":
        lost = source.chunk_messages[i] if source.compressed[i] else []
        return Mutant(f"chunk {i} header zeroed", _zero(raw, start, start + 30),
                      _without(everything, lost))  # fmt: skip
    if kind == "chunk_times":
        damaged = bytearray(raw)
        damaged[start + 9 + (pick // len(source.chunks)) % 16] ^= 1 << (bit % 8)
        return Mutant(f"chunk {i} times flipped", bytes(damaged), everything)
    if kind == "message_index":
        _, length = struct.unpack_from("<BQ", raw, start)
        at = start + 9 + length  # the first message index after the chunk
        if at >= end or raw[at] != mcap_format.OP_MESSAGE_INDEX:
            return None
        return Mutant(f"message index at {at} zeroed", _zero(raw, at, at + 9), everything)
    if kind == "swap":
        if len(source.chunks) < 2:
            return None
        j = (i + 1 + (pick // len(source.chunks)) % (len(source.chunks) - 1)) % len(source.chunks)
        i, j = sorted((i, j))
        return Mutant(f"chunks {i} and {j} swapped",
                      swap_spans(raw, source.chunks[i], source.chunks[j]), everything)  # fmt: skip
    raise AssertionError(kind)
