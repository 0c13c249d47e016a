"""Goal ids as actionlib's ``GoalIDGenerator`` makes them: ``/node-N-secs.nsecs``."""

from __future__ import annotations

import itertools
import threading

from rostools.msgs.message import Time

# One count per process, as actionlib keeps it: ids stay unique across clients of one node.
_COUNT = itertools.count(1)
_LOCK = threading.Lock()


def goal_id(node_name: str, now: Time | None = None) -> tuple[str, Time]:
    """A new goal id for ``node_name`` and the stamp it carries."""
    stamp = now if now is not None else Time.now()
    with _LOCK:
        n = next(_COUNT)
    return f"{node_name}-{n}-{stamp.secs}.{stamp.nsecs}", stamp
