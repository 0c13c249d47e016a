"""Delay and rate per frame and per broadcaster, as ``tf_monitor`` (``tf2_monitor``) counts them.

For each message received: each transform's delay is the receive time less its stamp (0 on
``/tf_static``), kept per child frame; the message's mean delay and its receive time are kept
per broadcaster (a static one apart, as tf_monitor's ``(static)``). Each list keeps the last
``WINDOW`` values, as tf_monitor's. A broadcaster's rate is its messages over the span between
the first and last kept (tf_monitor's count over span; none for a static one, whose latched
message comes once per subscriber). The chain between two frames gets its net delay: the
receive time less the newest time at which the whole chain is known.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

from rostools.tf.edges import Edges
from rostools.tf.records import Stamped

#: Values kept per frame and per broadcaster (tf_monitor's 1000).
WINDOW = 1000


@dataclass(slots=True)
class _Series:
    """The last ``WINDOW`` delays (s), and for a broadcaster its receive times (ns)."""

    delays: deque[float] = field(default_factory=lambda: deque(maxlen=WINDOW))
    times: deque[int] = field(default_factory=lambda: deque(maxlen=WINDOW))

    def summary(self) -> dict[str, float]:
        return {
            "average_delay": sum(self.delays) / len(self.delays),
            "max_delay": max(0.0, *self.delays),
        }


class Monitor:
    """What ``tf monitor`` reports, fed each ``/tf`` and ``/tf_static`` message."""

    def __init__(self) -> None:
        self._frames: dict[str, _Series] = {}
        self._authority: dict[str, str] = {}
        self._broadcasters: dict[tuple[str, bool], _Series] = {}
        #: The tree as tf2's buffer keeps it: the chain walks it.
        self.edges = Edges()
        self._net: list[float] = []

    def add(self, received_ns: int, broadcaster: str, static: bool, batch: list[Stamped]) -> None:
        """One message: ``batch`` from ``broadcaster``, received at ``received_ns``."""
        total = 0.0
        for t in batch:
            delay = 0.0 if static else (received_ns - t.stamp_ns) / 1e9
            total += delay
            self._frames.setdefault(t.child, _Series()).delays.append(delay)
            self._authority[t.child] = broadcaster
        who = self._broadcasters.setdefault((broadcaster, static), _Series())
        who.delays.append(total / max(1, len(batch)))
        who.times.append(received_ns)
        self.edges.add(batch, broadcaster, static)

    def chain(self, source: str, target: str) -> list[str] | None:
        """The frames from ``source`` to ``target`` through their common ancestor, or None."""
        up_s, up_t = self._up(source), self._up(target)
        common = next((f for f in up_s if f in set(up_t)), None)
        if common is None:
            return None
        down = up_t[: up_t.index(common)]
        return up_s[: up_s.index(common) + 1] + down[::-1]

    def _up(self, frame: str) -> list[str]:
        """``frame`` and its ancestors, to the root (a loop is cut where it closes)."""
        out = [frame]
        while (edge := self.edges.by_child.get(out[-1])) is not None and edge.parent not in out:
            out.append(edge.parent)
        return out

    def sample_chain(self, chain: list[str], now_ns: int) -> float | None:
        """Keep and return the chain's net delay now: ``now`` less its newest common stamp."""
        stamps = [
            e.newest_ns
            for f in chain
            if (e := self.edges.by_child.get(f)) is not None and not e.static
        ]
        # a chain static all along is known at any time
        delay = (now_ns - min(stamps)) / 1e9 if stamps else 0.0
        self._net.append(delay)
        return delay

    def report(self, chain: list[str] | None = None) -> dict[str, object]:
        """Frames (those of ``chain`` only, if given) and broadcasters, as tf_monitor lists them."""
        frames = [
            {"frame": name, "broadcaster": self._authority[name], **series.summary()}
            for name, series in sorted(self._frames.items())
            if chain is None or name in chain
        ]
        broadcasters = []
        for (name, static), series in sorted(self._broadcasters.items()):
            span = (series.times[-1] - series.times[0]) / 1e9
            rate = None if static else len(series.times) / max(span, 1e-8)
            broadcasters.append(
                {"broadcaster": name, "static": static, "rate": rate, **series.summary()}
            )
        out: dict[str, object] = {"frames": frames, "broadcasters": broadcasters}
        if chain is not None:
            net = self._net or [0.0]
            out["chain"] = chain
            out["net_delay"] = {"average": sum(net) / len(net), "max": max(net)}
        return out
