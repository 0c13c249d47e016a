"""Writing rosbag v2.0 files that real ROS reads, reindexes and plays.

The layout is rosbag's: a bag header padded to 4096 bytes of header plus data (so the first
chunk starts at 4117 and ``rosbag reindex`` can rewrite the header in place), chunks of about
768 KiB each followed by one INDEX_DATA record per connection, then CONNECTION and CHUNK_INFO
records, and the header rewritten last. LZ4 chunks use roslz4's frame settings.

Crash tolerance: every chunk is handed to the OS as soon as it closes. An uncompressed chunk
is written as rosbag's C++ recorder does it: a provisional chunk header (size 0), then its
records as they arrive, the header patched when the chunk closes; a killed writer leaves
every record that reached the OS readable by ``recover``. Compressed chunks are lost only for
the part still being collected.
"""

from __future__ import annotations

import struct
from array import array
from pathlib import Path
from typing import Final

from rostools.bag.formats import rosbag1_format as fmt
from rostools.bag.formats.base import BagWriter
from rostools.bag.formats.model import NS_PER_SEC, BagUsageError, Connection, UnsupportedBagError
from rostools.bag.formats.sink import little_endian
from rostools.wire.header import encode_fields

#: Pending output is handed to the OS in pieces of this size (and at every chunk close, and
#: on ``flush``): a SIGKILL loses at most this much of an uncompressed chunk.
FLUSH_SIZE: Final = 64 * 1024
#: The last time a bag can hold: u32 seconds.
MAX_BAG_TIME_NS: Final = (1 << 32) * NS_PER_SEC - 1

_U32 = fmt.U32
#: secs, nsecs, data_len: the tail of a message record header after the fixed prefix.
_MSG_TAIL = struct.Struct("<III")
_OP = {op: bytes([op]) for op in range(1, 8)}


class Bag1Writer(BagWriter):
    """A rosbag v2.0 file being written; see the module docstring."""

    def __init__(
        self,
        path: str | Path,
        *,
        compression: str = "none",
        chunk_size: int = fmt.DEFAULT_CHUNK_SIZE,
        overwrite: bool = False,
    ) -> None:
        if compression not in fmt.COMPRESSIONS:
            raise UnsupportedBagError(
                f"unknown .bag compression {compression!r} (use none, bz2 or lz4)"
            )
        if chunk_size <= 0:
            raise BagUsageError(f"chunk size must be positive, not {chunk_size}")
        super().__init__(path, overwrite)
        self.compression = compression
        self.chunk_size = chunk_size
        self._plain = compression == "none"  # records go straight to the file
        self._prefixes: list[bytes] = []
        self._in_file: set[int] = set()
        self._chunk_infos: list[tuple[int, int, int, dict[int, int]]] = []
        self._chunk_open = False
        self._chunk_pos = 0
        self._chunk_data_pos = 0
        self._chunk_buf = bytearray()
        self._chunk_len = 0
        self._chunk_start = 0
        self._chunk_end = 0
        self._chunk_index: dict[int, array[int]] = {}
        try:
            self._sink.write(fmt.MAGIC)
            self._sink.write(self._bag_header(0, 0, 0))
            self._sink.flush()
        except BaseException:
            self.abort()  # a disk already full: no file, and no open descriptor
            raise

    # -- the public interface --------------------------------------------------------------

    def _declare(self, conn: Connection) -> None:
        """Written into the chunk of its first message; here only its record prefix."""
        if conn.encoding != "ros1":  # callers convert or refuse first; never write CDR bytes
            raise UnsupportedBagError(
                f"{conn.topic} holds {conn.encoding} messages; a .bag holds only ROS 1 ones"
            )
        # Every message record header of this connection: conn, op, then time (sorted).
        self._prefixes.append(
            _U32.pack(38)
            + _U32.pack(9)
            + b"conn="
            + _U32.pack(conn.id)
            + _U32.pack(4)
            + b"op=\x02"
            + _U32.pack(13)
            + b"time="
        )

    def _store(self, cid: int, t_ns: int, data: bytes | bytearray | memoryview) -> None:
        if not 0 <= t_ns <= MAX_BAG_TIME_NS:
            raise BagUsageError(f"time {t_ns} ns does not fit a .bag (0 to 2^32 s)")
        if not self._chunk_open:
            self._open_chunk(t_ns)
        elif t_ns < self._chunk_start:
            self._chunk_start = t_ns
        elif t_ns > self._chunk_end:
            self._chunk_end = t_ns
        if cid not in self._in_file:
            self._in_file.add(cid)
            self._chunk_append(self._connection_record(self._connections[cid]))
        secs, nsecs = divmod(t_ns, NS_PER_SEC)
        index = self._chunk_index.get(cid)
        if index is None:
            index = self._chunk_index[cid] = array("I")
        index.extend((secs, nsecs, self._chunk_len))
        head = self._prefixes[cid] + _MSG_TAIL.pack(secs, nsecs, len(data))
        if self._plain:
            self._sink.write_record(head, data)
        else:
            self._chunk_buf += head
            self._chunk_buf += data
        self._chunk_len += 46 + len(data)  # u32 + 38-byte header + u32 + data
        if self._chunk_len >= self.chunk_size:
            self._close_chunk()
        elif self._sink.pending() >= FLUSH_SIZE:
            self._sink.flush()

    def flush(self) -> None:
        """Hand everything so far to the OS: after this, a killed writer loses none of it.

        An uncompressed chunk stays open (its records are already in the file); a compressed
        one is closed, since its data only exists once compressed.
        """
        self._check_open()
        if self._chunk_open and not self._plain:
            self._close_chunk()
        self._sink.flush()

    def close(self) -> None:
        """Close the last chunk, write the index, rewrite the bag header."""
        if self._closed:
            return
        try:
            if self._chunk_open:
                self._close_chunk()
            index_pos = self._sink.tell()
            for conn in self._connections:
                self._sink.write(self._connection_record(conn))
            for pos, start, end, counts in self._chunk_infos:
                self._sink.write(
                    fmt.encode_record(
                        {
                            "op": _OP[fmt.OP_CHUNK_INFO],
                            "ver": _U32.pack(fmt.INDEX_VERSION),
                            "chunk_pos": fmt.U64.pack(pos),
                            "start_time": fmt.pack_time(start),
                            "end_time": fmt.pack_time(end),
                            "count": _U32.pack(len(counts)),
                        },
                        b"".join(_U32.pack(c) + _U32.pack(n) for c, n in sorted(counts.items())),
                    )
                )
            self._sink.flush()
            header = self._bag_header(index_pos, len(self._connections), len(self._chunk_infos))
            self._sink.pwrite(header, len(fmt.MAGIC))
        finally:
            self._release()

    # -- records ---------------------------------------------------------------------------

    @staticmethod
    def _bag_header(index_pos: int, conn_count: int, chunk_count: int) -> bytes:
        header = fmt.encode_header(
            {
                "op": _OP[fmt.OP_BAG_HEADER],
                "index_pos": fmt.U64.pack(index_pos),
                "conn_count": _U32.pack(conn_count),
                "chunk_count": _U32.pack(chunk_count),
            }
        )
        padding = b" " * (fmt.BAG_HEADER_SPACE - len(header))
        return _U32.pack(len(header)) + header + _U32.pack(len(padding)) + padding

    @staticmethod
    def _connection_record(conn: Connection) -> bytes:
        return fmt.encode_record(
            {
                "op": _OP[fmt.OP_CONNECTION],
                "conn": _U32.pack(conn.id),
                "topic": conn.topic.encode(),
            },
            encode_fields(dict(conn.header())),
        )

    @staticmethod
    def _chunk_header(compression: str, size: int, data_len: int) -> bytes:
        header = fmt.encode_header(
            {
                "op": _OP[fmt.OP_CHUNK],
                "compression": compression.encode(),
                "size": _U32.pack(size),
            }
        )
        return _U32.pack(len(header)) + header + _U32.pack(data_len)

    # -- chunks ----------------------------------------------------------------------------

    def _open_chunk(self, t_ns: int) -> None:
        self._chunk_open = True
        self._chunk_pos = self._sink.tell()
        self._chunk_len = 0
        self._chunk_start = self._chunk_end = t_ns
        self._chunk_index = {}
        if self.compression == "none":
            # Provisional header (size 0, data length 0), patched on close, as rosbag does.
            self._sink.write(self._chunk_header("none", 0, 0))
            self._chunk_data_pos = self._sink.tell()

    def _chunk_append(self, record: bytes) -> None:
        if self._plain:
            self._sink.write(record)
        else:
            self._chunk_buf += record
        self._chunk_len += len(record)

    def _close_chunk(self) -> None:
        self._chunk_open = False
        index = self._chunk_index
        if self.compression == "none":
            self._sink.flush()
            header = self._chunk_header("none", self._chunk_len, self._chunk_len)
            self._sink.pwrite(header, self._chunk_pos)
        else:
            data = fmt.compress(self.compression, self._chunk_buf)
            self._sink.write(self._chunk_header(self.compression, self._chunk_len, len(data)))
            self._sink.write(data)
            self._chunk_buf = bytearray()
        for cid in sorted(index):
            entries = index[cid]
            self._sink.write(
                fmt.encode_record(
                    {
                        "op": _OP[fmt.OP_INDEX_DATA],
                        "ver": _U32.pack(fmt.INDEX_VERSION),
                        "conn": _U32.pack(cid),
                        "count": _U32.pack(len(entries) // 3),
                    },
                    little_endian(entries),
                )
            )
        counts = {cid: len(entries) // 3 for cid, entries in index.items()}
        self._chunk_infos.append((self._chunk_pos, self._chunk_start, self._chunk_end, counts))
        self._sink.flush()
