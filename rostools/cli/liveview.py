"""The live table of a command that runs until stopped: redrawn in place on stderr."""

from __future__ import annotations

import time
from collections.abc import Mapping
from typing import Protocol, TypeVar


class Counts(Protocol):
    """What a row has counted so far (a topic's ``TopicStats``, a client's subscription)."""

    @property
    def messages(self) -> int:
        """Messages so far."""
        ...

    @property
    def bytes(self) -> int:
        """Bytes so far."""
        ...


View = TypeVar("View", bound="LiveView")


class LiveView:
    """A table redrawn in place on stderr, at most twice a second, with each topic's rates.

    The live views of ``bag record``, ``bag snapshot`` and ``bridge``: a subclass says what it
    draws.
    """

    def __init__(self) -> None:
        from rich.console import Console
        from rich.live import Live

        self.live = Live(console=Console(stderr=True), auto_refresh=False, transient=False)
        #: Messages and bytes a second, per topic, over the last second or more.
        self.rates: dict[str, tuple[float, float]] = {}
        self._last: dict[str, tuple[float, int, int]] = {}
        self._next_draw = 0.0

    def __enter__(self: View) -> View:
        self.live.__enter__()
        return self

    def __exit__(self, *exc: object) -> None:
        self.live.__exit__(None, None, None)

    def due(self, force: bool = False) -> bool:
        """Whether to redraw now: half a second after the last time, or when ``force``."""
        now = time.monotonic()
        if now < self._next_draw and not force:
            return False
        self._next_draw = now + 0.5
        return True

    def measure(self, stats: Mapping[str, Counts], started: float, now: float) -> None:
        """Update each topic's rates from what it received (``stats``) since the last second."""
        for topic, s in stats.items():
            t0, m0, b0 = self._last.get(topic, (started, 0, 0))
            if now - t0 >= 1.0:
                self.rates[topic] = ((s.messages - m0) / (now - t0), (s.bytes - b0) / (now - t0))
                self._last[topic] = (now, s.messages, s.bytes)
