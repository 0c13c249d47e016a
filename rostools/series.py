"""Time series for plots: samples by label, a rolling window, and thinning to what is drawn.

Pure arithmetic, like ``rates.py``: ``topic plot`` and ``bag plot`` feed (x, y) pairs in, the
CLI draws what ``columns`` gives back. Samples are kept in ``array('d')`` pairs, so adding
one is an append and a window is a slice, and drawing a frame touches each sample once in
C (``bisect``, ``min``, ``max`` over slices), never in a Python loop per sample.
"""

from __future__ import annotations

import math
from array import array
from bisect import bisect_left
from collections.abc import Callable
from math import isfinite
from typing import Final

#: Samples one series keeps before thinning its oldest half (about 3 MB). A 10 s window at
#: 10 kHz holds 100,000; a whole bag or a long window at a high rate is thinned.
MAX_POINTS: Final = 200_000


class Series:
    """One line of a plot: x (seconds) and y, in arrival order.

    ``window``: seconds of x to keep behind the newest sample (None keeps everything);
    past ``max_points`` samples the window is applied, then the oldest half thinned.
    """

    __slots__ = ("max_points", "thinned", "window", "xs", "ys")

    def __init__(self, window: float | None = None, max_points: int = MAX_POINTS) -> None:
        self.xs = array("d")
        self.ys = array("d")
        self.window = window
        self.max_points = max_points
        #: Whether some samples were merged away (``MAX_POINTS``).
        self.thinned = False

    def __len__(self) -> int:
        return len(self.xs)

    def add(self, x: float, y: float) -> None:
        """One sample; NaN and infinities are not drawn, and not kept."""
        if not isfinite(y):
            return
        xs = self.xs
        xs.append(x)
        self.ys.append(y)
        if len(xs) > self.max_points:
            if self.window is not None:
                self.trim(x - self.window)
            if len(self.xs) > self.max_points:
                self.thin()

    def trim(self, lo: float) -> None:
        """Forget samples before ``lo`` (x is assumed to grow, as arrival times do)."""
        cut = bisect_left(self.xs, lo)
        if cut:
            del self.xs[:cut]
            del self.ys[:cut]

    def thin(self) -> None:
        """Halve the older half: each group of four becomes its lowest and highest sample.

        The envelope a plot shows survives; the newest samples stay as they came.
        """
        half = len(self.xs) // 2 // 4 * 4
        xs, ys = self.xs, self.ys
        kept_x, kept_y = array("d"), array("d")
        for i in range(0, half, 4):
            group = ys[i : i + 4]
            a = min(range(4), key=group.__getitem__)
            b = max(range(4), key=group.__getitem__)
            for j in sorted((a, b)) if a != b else (a,):
                kept_x.append(xs[i + j])
                kept_y.append(ys[i + j])
        self.xs = kept_x + xs[half:]
        self.ys = kept_y + ys[half:]
        self.thinned = True


class SeriesSet:
    """The series of one plot, by label, in the order declared, then of first samples.

    ``window`` and ``max_points`` apply to each series (``Series``).
    """

    def __init__(self, window: float | None = None, max_points: int = MAX_POINTS) -> None:
        self.window = window
        self.max_points = max_points
        self.series: dict[str, Series] = {}

    def declare(self, labels: list[str]) -> None:
        """Series to list in this order, before any sample: the order the user named them."""
        for label in labels:
            self.series.setdefault(label, Series(self.window, self.max_points))

    def sink(self, label: str) -> Callable[[float, float], None]:
        """Where the samples of ``label`` go: its series' ``add``, looked up once."""
        self.declare([label])
        return self.series[label].add

    def add(self, label: str, x: float, y: float) -> None:
        """One sample of ``label`` (``sink`` is the fast way for many)."""
        self.sink(label)(x, y)

    @property
    def newest(self) -> float:
        """The largest x held (-inf when there is nothing): a rolling window's right edge."""
        return max((s.xs[-1] for s in self.series.values() if len(s)), default=-math.inf)

    def trim(self, now: float | None = None) -> None:
        """Drop what has left the window that ends at ``now`` (default: the newest sample)."""
        if self.window is None:
            return
        edge = self.newest if now is None else max(now, self.newest)
        for s in self.series.values():
            s.trim(edge - self.window)

    def bounds(self) -> tuple[float, float] | None:
        """The smallest and largest x held, or None when there is nothing."""
        held = [s for s in self.series.values() if len(s)]
        if not held:
            return None
        return min(s.xs[0] for s in held), max(s.xs[-1] for s in held)


def columns(series: Series, lo: float, hi: float, width: int) -> tuple[list[float], list[float]]:
    """What a plot ``width`` columns wide over [lo, hi] needs to draw ``series``.

    Few samples come back as they are. Past two a column, each column gives its lowest and
    highest sample (in their order), so spikes survive and the work is one pass in C.
    """
    xs, ys = series.xs, series.ys
    first, last = bisect_left(xs, lo), len(xs)
    if last - first <= 2 * width or hi <= lo:
        return list(xs[first:last]), list(ys[first:last])
    out_x: list[float] = []
    out_y: list[float] = []
    step = (hi - lo) / width
    start = first
    for c in range(1, width + 1):
        end = last if c == width else bisect_left(xs, lo + c * step, start, last)
        if end > start:
            chunk = ys[start:end]
            low, high = min(chunk), max(chunk)
            i_low, i_high = chunk.index(low), chunk.index(high)
            for i in sorted({i_low, i_high}):
                out_x.append(xs[start + i])
                out_y.append(chunk[i])
        start = end
    return out_x, out_y
