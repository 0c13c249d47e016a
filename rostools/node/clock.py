"""ROS time: the ``/clock`` topic when ``/use_sim_time`` is set, else the wall clock."""

from __future__ import annotations

import struct
import sys
import time
from typing import TYPE_CHECKING

from rostools.msgs.wellknown import CLOCK
from rostools.node.connection import Frame, InboundConnection

if TYPE_CHECKING:
    from rostools.node.node import LiveNode
    from rostools.node.subscriber import FramesCallback

TIME = struct.Struct("<II")


async def uses_sim_time(node: LiveNode) -> bool:
    """Whether the parameter ``/use_sim_time`` is true."""
    if not await node.master.has_param("/use_sim_time"):
        return False
    value = await node.master.get_param("/use_sim_time")
    return value is True or str(value).lower() == "true"


#: prctl options (linux/prctl.h): the slack the kernel may add to a sleep's wake-up.
PR_SET_TIMERSLACK, PR_GET_TIMERSLACK = 29, 30
#: The slack that paced senders ask for, in ns. Linux's default is 50 us: a ``time.sleep``
#: wakes up to 50 us late, which at 1 kHz is half the error budget of ``bag play``.
TIMER_SLACK_NS = 1000


def tighten_timer_slack() -> bool:
    """Ask Linux to wake this thread's sleeps within ``TIMER_SLACK_NS``; False elsewhere."""
    if not sys.platform.startswith("linux"):
        return False
    import ctypes

    libc = ctypes.CDLL(None, use_errno=True)  # the interpreter's own symbols include libc's
    return bool(libc.prctl(PR_SET_TIMERSLACK, TIMER_SLACK_NS, 0, 0, 0) == 0)


class RosClock:
    """Now, in ns of ROS time; ``valid`` once sim time has had its first ``/clock``.

    ``forward`` receives the ``/clock`` frames too, for a node that also records them: a
    node subscribes to a topic once.
    """

    def __init__(self) -> None:
        self.sim = False
        self.last_ns = 0
        self.forward: FramesCallback | None = None

    async def start(self, node: LiveNode) -> None:
        """Follow ``/clock`` if ``/use_sim_time`` says so."""
        self.sim = await uses_sim_time(node)
        if self.sim:
            await node.subscribe("/clock", self._frames, CLOCK)

    @property
    def valid(self) -> bool:
        """Whether ``now`` means anything yet (sim time starts at zero, as ROS's)."""
        return not self.sim or self.last_ns > 0

    def now(self) -> int:
        """ROS time now, in ns."""
        return self.last_ns if self.sim else time.time_ns()

    def _frames(self, frames: list[Frame], conn: InboundConnection, now: float) -> None:
        if frames and len(frames[-1]) >= TIME.size:
            secs, nsecs = TIME.unpack_from(frames[-1])
            self.last_ns = secs * 1_000_000_000 + nsecs
        if self.forward is not None:
            self.forward(frames, conn, now)
