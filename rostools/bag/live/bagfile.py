"""One output file of a live recording: written as ``NAME.active``, renamed when complete.

``bag record`` and ``bag snapshot`` write through it: raw frames against the connection
header they came with, handed to the OS every ``FLUSH_PERIOD`` so that a writer killed
outright loses at most that much (``bag recover`` gets back the rest), and a failed write
turned into one line that says where what was written is kept.
"""

from __future__ import annotations

import time
from collections.abc import Hashable, Mapping
from pathlib import Path

from rostools.bag.formats.access import open_writer
from rostools.bag.formats.model import Connection
from rostools.bag.formats.sink import Buffer, WriteError
from rostools.errors import DataLossError

#: How often a file is handed to the OS, bounding what a crash can lose.
FLUSH_PERIOD = 1.0


def active_name(path: Path) -> Path:
    """Where ``path`` is written until it is closed (rosbag's ``.active``)."""
    return path.with_name(path.name + ".active")


class BagFile:
    """A bag being written as ``NAME.active``; ``close`` completes it under ``NAME``."""

    def __init__(
        self, path: Path, format: str, compression: str | None, chunk_size: int | None
    ) -> None:
        self.path = path
        self.active = active_name(path)
        self.writer = open_writer(self.active, format, compression, chunk_size)
        self._connections: dict[Hashable, Connection] = {}
        self._started()

    def _started(self) -> None:
        """Nothing written yet; the flush clock starts now."""
        self.messages = 0
        self.bytes = 0
        #: The receive times of the first and last message written (ns), once there is one.
        self.first_ns: int | None = None
        self.last_ns: int | None = None
        self._last_flush = time.monotonic()

    def write(
        self, key: Hashable, topic: str, header: Mapping[str, str], t_ns: int, data: Buffer
    ) -> None:
        """Store one raw message of the connection ``key`` (its header, declared once)."""
        conn = self._connections.get(key)
        if conn is None:
            conn = self._connections[key] = self.writer.connection_for(topic, header)
        self.writer.write(conn, t_ns, data)
        self._written(t_ns, data)

    def _written(self, t_ns: int, data: Buffer) -> None:
        """Count one message written."""
        self.messages += 1
        self.bytes += len(data)
        if self.first_ns is None:
            self.first_ns = t_ns
        self.last_ns = t_ns

    def flush_if_due(self) -> None:
        """Hand the file to the OS when ``FLUSH_PERIOD`` has passed since the last time."""
        if time.monotonic() - self._last_flush > FLUSH_PERIOD:
            self._flush()
            self._last_flush = time.monotonic()

    def _flush(self) -> None:
        self.writer.flush()

    def close(self) -> None:
        """Finish the file and give it its name."""
        self.writer.close()
        self.active.replace(self.path)


def write_failure(err: BaseException, what: str = "the recording stopped") -> BaseException:
    """What to raise for a writer's error: a failed write says what is kept, and where."""
    if not isinstance(err, WriteError):
        return err
    active = Path(err.path)
    space = "free some space" if err.disk_full else None
    if active.exists():
        failure = DataLossError(
            f"{err}: {what}; what was written stays in {active}",
            hint=f"{space}, then run 'rostools bag recover {active}'"
            if space
            else f"run 'rostools bag recover {active}'",
        )
    else:  # a new file (the first, or a split) that could not even be started
        failure = DataLossError(f"{err}: {what}", hint=space)
    failure.__cause__ = err
    return failure
