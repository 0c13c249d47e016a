"""The reaper: stops a test run's processes when the run dies without stopping them.

pytest killed outright (SIGKILL; or SIGTERM, which Python does not turn into an exception)
runs no fixture's teardown, and the processes ``ros_process`` started live in sessions of
their own, so a signal to pytest's process group does not reach them either. So the first
``RosProcess`` of a process also starts one reaper, ``python -I reaper.py``, with a pipe on
its standard input that only the starting process holds open. It writes ``+PGID`` for each
process group it starts and ``-PGID`` once it has stopped it. When the pipe closes (the
process is gone, however it died) the reaper sends SIGTERM to every group still listed,
SIGKILL after ``GRACE`` seconds to any that remain, and exits.

Not PR_SET_PDEATHSIG: it fires when the *thread* that started the child ends (a node started
from a helper thread would die with the thread), is Linux-only, and does not reach what a
launcher started. This file runs as a script on the standard library alone.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import time
from types import FrameType

#: Seconds between SIGTERM and SIGKILL.
GRACE = 2.0


def stop_groups(groups: set[int], grace: float = GRACE) -> None:
    """SIGTERM to each process group, then SIGKILL to those still there after ``grace`` s."""
    for group in groups:
        _signal(group, signal.SIGTERM)
    deadline = time.monotonic() + grace
    left = set(groups)
    while left and time.monotonic() < deadline:
        left = {g for g in left if _signal(g, 0)}
        time.sleep(0.05)
    for group in left:
        _signal(group, signal.SIGKILL)


def _signal(group: int, sig: int) -> bool:
    """Send ``sig`` to ``group``; whether the group still exists (a zombie counts)."""
    try:
        os.killpg(group, sig)
    except (ProcessLookupError, PermissionError):
        return False
    return True


def _stop_now(signum: int, frame: FrameType | None) -> None:
    raise SystemExit(0)


def main() -> int:
    """Read ``+PGID``/``-PGID`` lines until end of file, then stop the groups still listed."""
    # Ctrl-C is pytest's to handle (it stops its processes itself); a SIGTERM or SIGHUP sent
    # here too (a CI job cancelled as a whole) stops the groups at once.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, _stop_now)
    signal.signal(signal.SIGHUP, _stop_now)
    groups: set[int] = set()
    try:
        for line in sys.stdin.buffer:
            with contextlib.suppress(ValueError):
                group = int(line[1:])
                if line.startswith(b"+") and group > 1:
                    groups.add(group)
                elif line.startswith(b"-"):
                    groups.discard(group)
    finally:
        for sig in (signal.SIGTERM, signal.SIGHUP):  # a second signal must not cut this short
            signal.signal(sig, signal.SIG_IGN)
        stop_groups(groups)
    return 0


if __name__ == "__main__":
    sys.exit(main())
