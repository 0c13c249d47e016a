"""What steers ``bag play`` from the graph: ``--rate-control-topic`` and ``~pause_playback``.

Both behave as rosbag play's: playback is held while the rate-control topic's newest header
stamp lags bag time by more than the allowed delay, and ``std_srvs/SetBool`` on
``~pause_playback`` pauses (true) or resumes (false).
"""

from __future__ import annotations

import logging
import struct
from collections.abc import Callable

from rostools.bag.formats.model import NS_PER_SEC
from rostools.node.connection import Frame, InboundConnection
from rostools.node.node import LiveNode

log = logging.getLogger(__name__)

_STAMP = struct.Struct("<II")  # header.stamp, after the u32 seq


def header_first(definition: str) -> bool:
    """Whether a message definition starts with a ``Header`` field (comments skipped).

    rosbag accepts only ``Header``; ``std_msgs/Header``, as many definitions spell it, is the
    same type.
    """
    for line in definition.splitlines():
        words = line.split("#", 1)[0].split()
        if words:
            return words[0] in ("Header", "std_msgs/Header")
    return False


class RateControl:
    """The newest ``header.stamp`` seen on the rate-control topic, in ns."""

    def __init__(self, topic: str, max_delay: float, on_stamp: Callable[[], None]) -> None:
        self.topic = topic
        self.max_delay_ns = round(max_delay * NS_PER_SEC)
        self.on_stamp = on_stamp
        self.last_ns: int | None = None
        self._warned = False

    async def subscribe(self, node: LiveNode) -> None:
        """Listen on the topic (any type with a Header first)."""
        await node.subscribe(self.topic, self._frames)

    def start(self, t_ns: int) -> None:
        """Playback starts at bag time ``t_ns``: count the delay from there."""
        if self.last_ns is None:
            self.last_ns = t_ns

    def lag(self, t_ns: int) -> float:
        """How far (s) bag time ``t_ns`` is ahead of the newest stamp."""
        return max(t_ns - (self.last_ns if self.last_ns is not None else t_ns), 0) / NS_PER_SEC

    def holds(self, t_ns: int) -> bool:
        """Whether a message at bag time ``t_ns`` must wait."""
        return self.last_ns is not None and t_ns - self.last_ns > self.max_delay_ns

    def _frames(self, frames: list[Frame], conn: InboundConnection, _: float) -> None:
        definition = (conn.header or {}).get("message_definition", "")
        if not header_first(definition):
            if not self._warned:
                self._warned = True
                log.warning("the rate control topic's type has no Header first; ignored")
            return
        for frame in frames:
            if len(frame) >= 12:
                secs, nsecs = _STAMP.unpack_from(frame, 4)
                self.last_ns = secs * NS_PER_SEC + nsecs
        self.on_stamp()


def set_bool_reply(request: bytes, paused: bool, set_paused: Callable[[bool], None]) -> bytes:
    """Answer ``~pause_playback`` as rosbag play does, pausing or resuming on the way."""
    want = request[:1] not in (b"", b"\x00")
    changed = want != paused
    if changed:
        set_paused(want)
        message = f"Playback is now {'paused' if want else 'resumed'}"
    else:
        message = f"Bag is already {'paused.' if want else 'running.'}"
    text = message.encode()
    return struct.pack("<?I", changed, len(text)) + text
