"""Stand-ins for what a TCPROS connection talks to, for tests that feed it bytes directly."""

from __future__ import annotations

import asyncio
from typing import Any


class FakeTransport(asyncio.Transport):
    """Enough of a transport to feed a protocol bytes, see what it writes and see it close."""

    def __init__(self, sock: Any = None) -> None:
        super().__init__()
        self.sock = sock  # what get_extra_info("socket") gives, if anything
        self.closed = False
        self.written = b""

    def write(self, data: Any) -> None:
        self.written += bytes(data)

    def close(self) -> None:
        self.closed = True

    def abort(self) -> None:
        self.closed = True

    def is_closing(self) -> bool:
        return self.closed

    def get_extra_info(self, name: str, default: Any = None) -> Any:
        if name == "socket" and self.sock is not None:
            return self.sock
        return ("127.0.0.1", 1) if name == "peername" else default

    def set_write_buffer_limits(self, high: Any = None, low: Any = None) -> None:
        pass


class FrameHandler:
    """A service's side of an accepted connection: the frames after the header."""

    def __init__(self) -> None:
        self.frames: list[bytes] = []

    def frames_received(self, frames: list[Any]) -> None:
        self.frames += [bytes(f) for f in frames]

    def connection_lost(self) -> None:
        pass

    def pause_writing(self) -> None:
        pass

    def resume_writing(self) -> None:
        pass
