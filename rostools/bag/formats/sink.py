"""Output for the bag writers: small records coalesced, large payloads passed without copies.

A big message (an image, a point cloud) read from another bag is a memoryview into that file's
map; it is queued as is and handed to the kernel with ``os.writev``, so converting a bag copies
its bytes once (into the page cache) instead of three or four times through Python buffers.
"""

from __future__ import annotations

import errno
import os
import sys
from array import array
from typing import Final

from rostools.errors import InvalidDataError

#: Payloads at least this big are queued by reference rather than copied into the buffer.
BIG_PAYLOAD: Final = 16 * 1024
#: ``writev`` takes at most IOV_MAX (1024 on Linux) buffers per call.
_IOV_MAX: Final = min(os.sysconf("SC_IOV_MAX") if hasattr(os, "sysconf") else 1024, 1024)

Buffer = bytes | bytearray | memoryview

#: What the OS said, in the words a user needs (the rest say ``strerror``).
_CAUSES: Final = {
    errno.ENOSPC: "the disk is full",
    errno.EDQUOT: "the disk quota is used up",
    errno.EFBIG: "the file is larger than the file system or the size limit (ulimit -f) allows",
}


class WriteError(InvalidDataError):
    """The OS refused to write a bag file: a full disk, a size limit, an I/O error.

    ``errno`` is the OS's error number. Once a write has failed, the file's tail is not known,
    so the sink writes nothing more: what is in the file stays readable by ``bag recover``.
    """

    def __init__(self, path: str, err: OSError) -> None:
        self.path = path
        self.errno = err.errno
        why = err.strerror or str(err)
        cause = _CAUSES.get(err.errno or 0)
        super().__init__(f"cannot write {path}: " + (f"{cause} ({why})" if cause else why))

    @property
    def disk_full(self) -> bool:
        """Whether the disk (or the user's quota) is full."""
        return self.errno in (errno.ENOSPC, errno.EDQUOT)


def frozen(data: Buffer) -> bytes | memoryview:
    """``data`` if it cannot change under us (bytes, a read-only view), else a copy.

    Queued payloads are written later; a caller's reused bytearray must not change them.
    """
    if isinstance(data, memoryview):
        if data.format != "B" or data.ndim != 1:
            data = data.cast("B")
        if data.readonly:
            return data
        return bytes(data)
    if isinstance(data, bytes):
        return data
    return bytes(data)


class Sink:
    """Appends to a file descriptor; ``tell`` counts queued bytes too."""

    def __init__(self, fd: int, name: str) -> None:
        self.fd = fd
        self.name = name
        self.written = 0  # bytes handed to the OS
        self._queue: list[Buffer] = []
        self._queued = 0
        self._small = bytearray()
        self._failed: WriteError | None = None

    def tell(self) -> int:
        """The file offset the next byte will have."""
        return self.written + self._queued + len(self._small)

    def pending(self) -> int:
        """Bytes not yet handed to the OS."""
        return self._queued + len(self._small)

    def write(self, data: Buffer) -> None:
        """Append bytes (big ones by reference: pass only data that will not change)."""
        if len(data) >= BIG_PAYLOAD:
            if self._small:
                self._queue.append(self._small)
                self._queued += len(self._small)
                self._small = bytearray()
            self._queue.append(data)
            self._queued += len(data)
        else:
            self._small += data

    def write_record(self, head: bytes, data: Buffer) -> None:
        """Append a record header and its payload (a big payload by reference, if immutable)."""
        if len(data) >= BIG_PAYLOAD:
            self._small += head
            self.write(frozen(data))
        else:
            self._small += head
            self._small += data

    def flush(self) -> None:
        """Hand everything to the OS."""
        if self._small:
            self._queue.append(self._small)
            self._queued += len(self._small)
            self._small = bytearray()
        if self._failed is not None:
            raise self._failed
        queue = self._queue
        i = 0
        try:
            while i < len(queue):
                done = os.writev(self.fd, queue[i : i + _IOV_MAX])
                self.written += done
                self._queued -= done
                while done:  # drop what was written; keep the rest of a partly written buffer
                    size = len(queue[i])
                    if done < size:
                        queue[i] = memoryview(queue[i])[done:]
                        break
                    done -= size
                    i += 1
        except OSError as err:
            raise self._fail(err) from err
        finally:
            del queue[:i]

    def pwrite(self, data: bytes, pos: int) -> None:
        """Overwrite bytes already handed to the OS (a header patched on close)."""
        if self._failed is not None:
            raise self._failed
        try:
            os.pwrite(self.fd, data, pos)
        except OSError as err:
            raise self._fail(err) from err

    def _fail(self, err: OSError) -> WriteError:
        """Remember the failure: a later flush would append after a tail that is not known."""
        self._failed = WriteError(self.name, err)
        return self._failed


def little_endian(values: array[int]) -> bytes:
    """The bytes of an integer array as the file formats want them (little-endian)."""
    if sys.byteorder == "big":
        values = array(values.typecode, values)
        values.byteswap()
    return values.tobytes()
