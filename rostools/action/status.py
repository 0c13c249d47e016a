"""Goal states as actionlib_msgs/GoalStatus numbers them, and the rule of a cancel request."""

from __future__ import annotations

PENDING, ACTIVE, PREEMPTED, SUCCEEDED, ABORTED, REJECTED = 0, 1, 2, 3, 4, 5
PREEMPTING, RECALLING, RECALLED, LOST = 6, 7, 8, 9

NAMES = (
    "PENDING", "ACTIVE", "PREEMPTED", "SUCCEEDED", "ABORTED", "REJECTED",
    "PREEMPTING", "RECALLING", "RECALLED", "LOST",
)  # fmt: skip
#: States a goal never leaves: the server has sent (or will never send) its result.
TERMINAL = frozenset((PREEMPTED, SUCCEEDED, ABORTED, REJECTED, RECALLED, LOST))
#: States of a goal whose cancel the server has taken.
CANCELING = frozenset((PREEMPTING, RECALLING))

GOAL_ID = "actionlib_msgs/GoalID"
STATUS = "actionlib_msgs/GoalStatus"
STATUS_ARRAY = "actionlib_msgs/GoalStatusArray"


def name(code: int) -> str:
    """``SUCCEEDED`` for 3; an unknown number as ``STATUS_<n>``."""
    return NAMES[code] if 0 <= code < len(NAMES) else f"STATUS_{code}"


def cancel_matches(cancel_id: str, cancel_stamp_ns: int, goal_id: str, goal_stamp_ns: int) -> bool:
    """Whether a cancel request (a GoalID) covers a goal, by actionlib's rule.

    An empty id and a zero stamp cancel every goal; an id cancels that goal; a stamp cancels
    every goal stamped at or before it. Id and stamp together cancel both sets.
    """
    if not cancel_id and cancel_stamp_ns == 0:
        return True
    if cancel_id and cancel_id == goal_id:
        return True
    return cancel_stamp_ns != 0 and goal_stamp_ns <= cancel_stamp_ns
