"""Paced senders (bag play, pub -r) and the kernel's timers."""

from __future__ import annotations

import sys

import pytest


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="timer slack is Linux's")
def test_paced_senders_tighten_timer_slack() -> None:
    """bag play and pub -r: Linux's default 50 us timer slack would make every sleep late."""
    import ctypes
    import threading

    from rostools.node.clock import PR_GET_TIMERSLACK, TIMER_SLACK_NS, tighten_timer_slack

    got: list[int] = []

    def probe() -> None:  # slack is per thread: leave the test runner's own alone
        assert tighten_timer_slack()
        got.append(ctypes.CDLL(None).prctl(PR_GET_TIMERSLACK, 0, 0, 0, 0))

    thread = threading.Thread(target=probe)
    thread.start()
    thread.join()
    assert got == [TIMER_SLACK_NS]


def test_pub_sends_each_message_when_due_and_flushes_it_alone(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    """``pub -r 5000`` on a clock of the test's own: every message leaves at its time and is
    flushed alone, and a wait shorter than 2 ms is slept, not left to the event loop, whose
    timers wake up to a millisecond late (issue 14: 10 kHz reached a roscpp subscriber in
    bursts every 1.3 ms). How evenly messages arrive on a real machine, beside rostopic, is
    benchmark ``pub_pacing``'s (benchmarks/bench_topic_cpp.py): it depends on the machine.
    """
    import asyncio
    import itertools
    import math
    from types import SimpleNamespace

    from rostools.cli.topic import pub
    from rostools.node import clock, session

    rate, span = 5000.0, 0.1
    now = [1000.0]

    def monotonic() -> float:
        now[0] += 1e-6  # each look at the clock costs a microsecond
        return now[0]

    def sleep(seconds: float) -> None:
        now[0] += seconds

    async def loop_wait(*waits: object, timeout: float | None = None) -> None:
        """The event loop's wait: its timer fires on the next whole millisecond."""
        for wait in waits:
            wait.close()  # type: ignore[attr-defined]  # stop.wait(), never set here
        assert timeout is not None
        now[0] = math.ceil((now[0] + timeout) * 1000) / 1000

    events: list[tuple[str, float]] = []
    publisher = SimpleNamespace(
        publish=lambda data: events.append(("publish", now[0])),
        flush=lambda: events.append(("flush", now[0])),
    )
    monkeypatch.setattr(pub, "time", SimpleNamespace(monotonic=monotonic, sleep=sleep))
    monkeypatch.setattr(session, "first", loop_wait)
    monkeypatch.setattr(clock, "tighten_timer_slack", lambda: True)  # the runner's thread's
    plan = SimpleNamespace(rate=rate, show=None, repeated=True, substitute=False)
    message = SimpleNamespace(serialize=lambda: b"\x01\x00\x00\x00x")
    end = now[0] + span

    asyncio.run(
        pub._paced(
            plan,  # type: ignore[arg-type]
            publisher,  # type: ignore[arg-type]
            itertools.repeat(message),
            lambda: end - now[0],
            asyncio.Event(),
        )
    )
    sent = [t for kind, t in events if kind == "publish"]
    assert abs(len(sent) - rate * span) <= 1, len(sent)
    gaps = [b - a for a, b in itertools.pairwise(sent)]
    assert max(abs(gap - 1 / rate) for gap in gaps) < 0.05 / rate, (min(gaps), max(gaps))
    # each one flushed before the next is published: none waits to leave with later ones
    kinds = [kind for kind, _ in events]
    assert all(a != b for a, b in itertools.pairwise(kinds[:-1])), kinds[:12]
