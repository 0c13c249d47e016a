"""Assertions about a live graph: a message that comes, a topic's rate.

They use the API's default node on ``ROS_MASTER_URI`` (the test's master under the
``ros_master`` fixture), and fail with what they saw, not only that time ran out.
"""

from __future__ import annotations

import collections
import threading
import time
from collections.abc import Callable, Mapping
from typing import Any

from rostools._api import loop
from rostools._api.functions import default_node
from rostools.errors import TimeoutExpired
from rostools.msgs.message import Message
from rostools.testing.readable import readable

#: The last message each helper saw, by topic: the plugin adds them to a failure's report.
last_seen: dict[str, Message] = {}
#: A rate is measured over at least this many seconds (and at least 10 intervals).
MIN_SPAN = 1.0

Predicate = Callable[[Message], object] | Mapping[str, object] | None


def _field(msg: Any, path: str) -> Any:
    for part in path.split("."):
        msg = msg[int(part)] if part.isdigit() else getattr(msg, part)
    return msg


def _matches(msg: Message, predicate: Predicate) -> bool:
    __tracebackhide__ = True  # a predicate that fails shows the test's line, then its own
    if predicate is None:
        return True
    if isinstance(predicate, Mapping):
        try:
            return all(_field(msg, k) == v for k, v in predicate.items())
        except (AttributeError, IndexError):
            return False
    return bool(predicate(msg))


def _publishers(topic: str) -> list[str]:
    node = default_node()
    try:
        state = loop.run(node.aio.core.master.system_state(), timeout=5)
    except Exception:  # noqa: BLE001 - only decorates the failure message
        return []
    name = node.resolve(topic)
    return next((list(nodes) for t, nodes in state[0] if t == name), [])


@readable
def assert_message(
    topic: str,
    predicate: Predicate = None,
    timeout: float = 5.0,
    msg_type: str | None = None,
) -> Message:
    """The first message on ``topic`` that satisfies ``predicate``, within ``timeout`` s.

    ``predicate`` is a function of the message, or a mapping of field paths to values
    (``{"linear.x": 1.0}``), or None for any message. A latched message counts. Fails with
    how many messages came, the last of them, and who publishes the topic.
    """
    __tracebackhide__ = True
    node = default_node()
    deadline = time.monotonic() + timeout
    seen = 0
    last: Message | None = None
    with node.subscribe(topic, msg_type=msg_type) as sub:
        while (left := deadline - time.monotonic()) > 0:
            try:
                msg = sub.get(left)
            except TimeoutExpired:
                break
            seen += 1
            last = last_seen[sub.topic] = msg
            if _matches(msg, predicate):
                return msg
    what = "" if predicate is None else " matching the predicate"
    got = f"{seen} came, the last: {last!r}" if seen else "none came"
    raise AssertionError(
        f"no message on {topic}{what} within {timeout:g} s: {got};"
        f" publishers: {_publishers(topic) or 'none'}"
    )


@readable
def assert_topic_rate(topic: str, hz: float, tolerance: float = 0.1, within: float = 10.0) -> float:
    """Wait until ``topic`` is published at ``hz`` give or take ``tolerance`` (a fraction).

    The rate is measured over the last ``max(1 s, 10 intervals)`` of arrivals, for up to
    ``within`` seconds; it returns the measured rate. Messages are counted, not decoded.
    """
    __tracebackhide__ = True
    if hz <= 0 or tolerance < 0:
        raise ValueError("hz must be above 0 and tolerance at least 0")
    node = default_node()
    span = max(MIN_SPAN, 10.0 / hz)
    arrivals: collections.deque[float] = collections.deque()
    lock = threading.Lock()

    def arrived(data: bytes, header: dict[str, str], now: float) -> None:
        with lock:
            arrivals.append(time.monotonic())

    undo = loop.run(node.aio.listen_raw(topic, arrived))
    started = time.monotonic()
    measured: float | None = None
    try:
        while time.monotonic() - started < within:
            time.sleep(0.02)
            with lock:
                if not arrivals:
                    continue
                newest = arrivals[-1]
                while len(arrivals) > 2 and newest - arrivals[1] >= span:
                    arrivals.popleft()  # keep the oldest arrival that still spans the window
                first, count = arrivals[0], len(arrivals)
            if newest - first < span * 0.999 or count < 3:
                continue
            measured = (count - 1) / (newest - first)
            if abs(measured - hz) <= tolerance * hz:
                return measured
    finally:
        loop.run(undo())
    if measured is None:
        with lock:
            count = len(arrivals)
        what = f"only {count} message(s)" if count else "no messages"
        raise AssertionError(
            f"{topic}: {what} in {within:g} s, expected {hz:g} Hz;"
            f" publishers: {_publishers(topic) or 'none'}"
        )
    raise AssertionError(
        f"{topic} is published at {measured:.3g} Hz, expected {hz:g} Hz ± {tolerance:.0%}"
        f" (measured over the last {span:g} s, for {within:g} s)"
    )
