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
