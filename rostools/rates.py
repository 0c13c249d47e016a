"""Rate, bandwidth and delay statistics with rostopic's definitions, fast enough for 200 kHz.

Messages are counted per receive batch: a batch of k messages that arrived at ``t`` after a
batch at ``t0`` contributes k intervals of ``(t - t0) / k``, so min/max/std stay meaningful at
rates where single messages cannot be timed from Python. Work is per batch, not per message.

``hz``'s average rate is the least-squares slope of message count over arrival time across the
window. On evenly timed arrivals that is rostopic's ``1 / mean interval``; but rostopic's
figure is decided by the arrival times of the window's first and last messages alone, and a
millisecond of scheduling delay on either moves it by a percent at 50 kHz. The fit weighs
every batch in the window, so that jitter averages out.
"""

from __future__ import annotations

import collections
import math
import time
from dataclasses import dataclass

#: rostopic's window when none is given (its -1 means 50000).
DEFAULT_WINDOW = 50000
#: ``hz`` without ``--window`` also keeps at least this many seconds (``RateMeter.min_span``).
DEFAULT_SPAN = 5.0


@dataclass(frozen=True)
class Stats:
    """One report: rostopic's (rate or mean, min, max, std dev, window)."""

    value: float
    min: float
    max: float
    std_dev: float
    window: int


def _summary(values: list[float]) -> tuple[float, float, float, float]:
    n = len(values)
    mean = math.fsum(values) / n
    std = math.sqrt(math.fsum((x - mean) ** 2 for x in values) / n)
    return mean, min(values), max(values), std


def _fit_rate(points: collections.deque[tuple[int, float]]) -> float | None:
    """Messages per second: the slope of arrival time over message number, inverted."""
    n = len(points)
    if n < 3:
        return None
    mx = sum(c for c, _ in points) / n
    my = sum(t for _, t in points) / n
    sxx = sxy = 0.0
    for c, t in points:
        dx = c - mx
        sxx += dx * dx
        sxy += dx * (t - my)
    return sxx / sxy if sxy > 0 else None


class RateMeter:
    """``hz``: intervals between arrivals over the last ``window`` messages.

    With ``min_span``, the window also holds at least the last ``min_span`` seconds: at 200 kHz
    rostopic's 50,000 messages are a quarter of a second, too short to average out a stall.
    """

    def __init__(self, window: int = DEFAULT_WINDOW, min_span: float = 0.0) -> None:
        #: Intervals the window holds: rostopic keeps ``window`` messages.
        self.size = max(window - 1, 1)
        self.min_span = min_span
        #: [k, interval, arrival]: k equal intervals from one batch, oldest first; ``held``
        #: intervals in all.
        self.steps: collections.deque[list[float]] = collections.deque()
        self.held = 0
        #: (number of the batch's last message, arrival time), oldest first.
        self.points: collections.deque[tuple[int, float]] = collections.deque()
        self.last: float | None = None
        self.count = 0
        self.reported_count = 0

    def add(self, count: int, now: float) -> None:
        """``count`` messages arrived at ``now``."""
        if count <= 0:
            return
        if self.last is None or now < self.last:  # first batch, or time went backwards
            self.steps.clear()
            self.points.clear()
            self.held = 0
            step = 0.0  # the rest of a first batch came with its first message
            count -= 1
            self.count += 1
        else:
            step = (now - self.last) / count
        self.last = now
        if count:
            self.steps.append([count, step, now])
            self.held += count
            self.count += count
        self.points.append((self.count, now))
        self._trim(now - self.min_span)

    def _trim(self, keep_after: float) -> None:
        excess = self.held - self.size
        steps = self.steps
        # A batch that ended min_span ago or earlier is outside the span; without a span
        # (an explicit -w) that is every batch, so the window is a count of messages even
        # when one read brings more than it holds.
        while excess > 0 and steps[0][2] <= keep_after:
            k = int(steps[0][0])
            if k <= excess:
                steps.popleft()
                self.held -= k
                excess -= k
            else:
                steps[0][0] = k - excess
                self.held -= excess
                excess = 0
        oldest = self.count - self.held  # the number of the window's first message
        while len(self.points) > 1 and self.points[0][0] < oldest:
            self.points.popleft()

    def report(self, again: bool = False) -> Stats | None:
        """The statistics, or None when nothing new arrived since the last report.

        ``again`` gives the window even then: the last report, on Ctrl-C.
        """
        if not self.held or (self.count == self.reported_count and not again):
            return None
        self.reported_count = self.count
        n = self.held
        mean = math.fsum(k * step for k, step, _ in self.steps) / n
        var = math.fsum(k * (step - mean) ** 2 for k, step, _ in self.steps) / n
        low = min(step for _, step, _ in self.steps)
        high = max(step for _, step, _ in self.steps)
        rate = _fit_rate(self.points)
        if rate is None:
            rate = 1.0 / mean if mean > 0 else 0.0
        return Stats(rate, low, high, math.sqrt(var), n + 1)


@dataclass(frozen=True)
class Bandwidth:
    """One ``bw`` report."""

    rate: float
    mean: float
    min: float
    max: float
    window: int


class BandwidthMeter:
    """``bw``: bytes per second over the last ``window`` messages (rostopic's definition)."""

    def __init__(self, window: int = 100) -> None:
        self.times: collections.deque[float] = collections.deque(maxlen=window)
        self.sizes: collections.deque[int] = collections.deque(maxlen=window)

    def add(self, sizes: list[int], now: float) -> None:
        """Messages of these sizes arrived at ``now``."""
        self.sizes.extend(sizes)
        self.times.extend([now] * len(sizes))

    def report(self, now: float | None = None) -> Bandwidth | None:
        """The bandwidth from the oldest message in the window until now; None until 2."""
        if len(self.times) < 2:
            return None
        now = time.monotonic() if now is None else now
        total = sum(self.sizes)
        span = now - self.times[0]
        n = len(self.sizes)
        rate = total / span if span > 0 else 0.0
        return Bandwidth(rate, total / n, float(min(self.sizes)), float(max(self.sizes)), n)


def format_bandwidth(bw: Bandwidth) -> str:
    """rostopic bw's two lines, with 1000-based units."""
    if bw.rate < 1000:
        unit, scale = "B", 1.0
    elif bw.rate < 1_000_000:
        unit, scale = "KB", 1000.0
    else:
        unit, scale = "MB", 1_000_000.0
    rate, mean, low, high = (f"{v / scale:.2f}{unit}" for v in (bw.rate, bw.mean, bw.min, bw.max))
    return f"average: {rate}/s\n\tmean: {mean} min: {low} max: {high} window: {bw.window}"


class DelayMeter:
    """``delay``: now minus ``header.stamp``, over the last ``window`` messages."""

    def __init__(self, window: int = DEFAULT_WINDOW) -> None:
        self.delays: collections.deque[float] = collections.deque(maxlen=max(window - 1, 1))
        self.count = 0
        self.reported_count = 0

    def add(self, delays: list[float]) -> None:
        """Delays in seconds of messages that just arrived."""
        self.delays.extend(delays)
        self.count += len(delays)

    def report(self, again: bool = False) -> Stats | None:
        """(mean delay, min, max, std dev, window), or None when nothing new arrived.

        ``again`` gives the window even then: the last report, on Ctrl-C.
        """
        if not self.delays or (self.count == self.reported_count and not again):
            return None
        self.reported_count = self.count
        mean, low, high, std = _summary(list(self.delays))
        return Stats(mean, low, high, std, len(self.delays) + 1)


def format_rate(stats: Stats) -> str:
    """rostopic hz's two lines."""
    return (
        f"average rate: {stats.value:.3f}\n\tmin: {stats.min:.3f}s max: {stats.max:.3f}s "
        f"std dev: {stats.std_dev:.5f}s window: {stats.window}"
    )


def format_delay(stats: Stats) -> str:
    """rostopic delay's two lines."""
    return (
        f"average delay: {stats.value:.3f}\n\tmin: {stats.min:.3f}s max: {stats.max:.3f}s "
        f"std dev: {stats.std_dev:.5f}s window: {stats.window}"
    )


def rate_table(rows: list[tuple[str, Stats]]) -> str:
    """rostopic hz's report for several topics: its table, then the blank line its print adds.

    Each row has its own window.
    """
    header = ["topic", "rate", "min_delta", "max_delta", "std_dev", "window"]
    cols = [
        [t, f"{s.value:.4}", f"{s.min:.4}", f"{s.max:.4}", f"{s.std_dev:.4}", str(s.window)]
        for t, s in rows
    ]
    widths = [max(len(h), *(len(c[i]) for c in cols)) for i, h in enumerate(header)]
    lines = ["   ".join(h.center(w) for h, w in zip(header, widths, strict=True))]
    lines.append("=" * (sum(widths) + 3 * (len(header) - 1)))
    lines += ["   ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)) for row in cols]
    return "\n".join(lines) + "\n\n"
