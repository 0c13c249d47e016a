"""The services of ``bag snapshot``, on the wire: rosbag_snapshot's trigger and std_srvs/Trigger.

``trigger_snapshot`` has ``rosbag_snapshot_msgs/TriggerSnapshot``'s type and md5sum, so
rosbag_snapshot's own clients can call it::

    string filename   # ends in .bag: that name; else a prefix for a dated name
    string[] topics   # empty: every buffered topic
    time start_time   # 0: from the oldest message buffered
    time stop_time    # 0: up to now
    ---
    string NO_DATA_MESSAGE=no messages buffered on selected topics
    bool success
    string message

Our extensions stay within that type: a ``stop_time`` in the future keeps writing live
messages until then, and ``FOREVER`` (the last second of ROS time) until stopped.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field

from rostools.errors import InvalidDataError, RostoolsError

NO_DATA_MESSAGE = "no messages buffered on selected topics"
#: ``stop_time`` seconds that mean "until stopped" (``bag trigger --continue``).
FOREVER_SECS = 0xFFFFFFFF
_U32 = struct.Struct("<I")
_TIME = struct.Struct("<II")


class TriggerError(RostoolsError):
    """A trigger that writes nothing: a bad name, too many files at once, no data, no disk."""


@dataclass
class SnapshotRequest:
    """A ``TriggerSnapshot`` request; times in ns (0: the default)."""

    filename: str = ""
    topics: list[str] = field(default_factory=list)
    start_ns: int = 0
    stop_ns: int = 0

    @property
    def forever(self) -> bool:
        """Whether the file is to be written until the snapshot is stopped."""
        return self.stop_ns >= FOREVER_SECS * 1_000_000_000

    def encode(self) -> bytes:
        """The request's bytes."""
        parts = [_string(self.filename), _U32.pack(len(self.topics))]
        parts += [_string(t) for t in self.topics]
        parts += [_time(self.start_ns), _time(self.stop_ns)]
        return b"".join(parts)

    @classmethod
    def decode(cls, data: bytes) -> SnapshotRequest:
        """Read a request; ``InvalidDataError`` for bytes that are not one."""
        reader = _Reader(data)
        filename = reader.string()
        topics = [reader.string() for _ in range(reader.count())]
        start, stop = reader.time(), reader.time()
        return cls(filename, topics, start, stop)


def window(
    now_ns: int, before: float | None, after: float, forever: bool = False
) -> tuple[int, int]:
    """``(start_ns, stop_ns)`` of a trigger at ``now_ns``: ``before`` s back, ``after`` s on.

    Every trigger works its window out here: ``bag trigger``, ``~trigger``, SIGUSR1, the ``s``
    key and the API. ``before`` None starts at the oldest message buffered (0); ``after`` 0
    stops at the trigger (0: "up to now"); ``forever`` writes until stopped.
    """
    start = max(now_ns - round(before * 1e9), 1) if before is not None else 0
    if forever:
        return start, FOREVER_SECS * 1_000_000_000
    return start, (now_ns + round(after * 1e9) if after else 0)


def encode_answer(success: bool, message: str) -> bytes:
    """The response of ``TriggerSnapshot`` and of ``std_srvs/Trigger`` (the same fields)."""
    return struct.pack("<?", success) + _string(message)


def decode_answer(data: bytes) -> tuple[bool, str]:
    """``(success, message)`` from a response of either type."""
    if not data:
        raise InvalidDataError("an empty answer")
    return data[0] != 0, _Reader(data[1:]).string()


def _string(text: str) -> bytes:
    raw = text.encode()
    return _U32.pack(len(raw)) + raw


def _time(t_ns: int) -> bytes:
    secs, nsecs = divmod(max(t_ns, 0), 1_000_000_000)
    return _TIME.pack(min(secs, FOREVER_SECS), nsecs)


class _Reader:
    """Reads a message's fields, refusing lengths the bytes do not hold."""

    def __init__(self, data: bytes) -> None:
        self.data = data
        self.pos = 0

    def _take(self, size: int) -> bytes:
        if self.pos + size > len(self.data):
            raise InvalidDataError(f"the request is cut short at byte {self.pos}")
        chunk = self.data[self.pos : self.pos + size]
        self.pos += size
        return chunk

    def count(self) -> int:
        (n,) = _U32.unpack(self._take(4))
        if n * 4 > len(self.data) - self.pos:  # each item takes 4 bytes at least
            raise InvalidDataError(f"a list of {n} items in {len(self.data)} bytes")
        return int(n)

    def string(self) -> str:
        (n,) = _U32.unpack(self._take(4))
        try:
            return self._take(n).decode()
        except UnicodeDecodeError as err:
            raise InvalidDataError(f"a string that is not UTF-8 ({err.reason})") from None

    def time(self) -> int:
        secs, nsecs = _TIME.unpack(self._take(8))
        return int(secs) * 1_000_000_000 + int(nsecs)
