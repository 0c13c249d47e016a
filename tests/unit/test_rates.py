"""Rate, bandwidth and delay statistics (rostopic's definitions)."""

from __future__ import annotations

import random

import pytest

from rostools.rates import (
    DEFAULT_SPAN,
    DEFAULT_WINDOW,
    BandwidthMeter,
    DelayMeter,
    RateMeter,
    format_bandwidth,
    format_rate,
    rate_table,
)


def test_rate_is_exact_whatever_the_batching() -> None:
    meter = RateMeter()
    t = 100.0
    meter.add(1, t)
    for batch in [1, 5, 50, 3, 200, 1] * 20:
        t += batch * 0.001  # 1 kHz, delivered in batches
        meter.add(batch, t)
    stats = meter.report()
    assert stats is not None
    assert stats.value == pytest.approx(1000.0, rel=1e-9)
    assert stats.min == pytest.approx(0.001) and stats.max == pytest.approx(0.001)
    assert meter.report() is None  # nothing new since


def test_rate_window_and_time_reset() -> None:
    meter = RateMeter(window=11)
    for i in range(100):
        meter.add(1, float(i))
    stats = meter.report()
    assert stats is not None and stats.window == 11 and stats.value == pytest.approx(1.0)
    meter.add(1, 5.0)  # time went backwards: start over
    meter.add(1, 5.5)
    stats = meter.report()
    assert stats is not None and stats.value == pytest.approx(2.0) and stats.window == 2


def test_rostopic_text_formats() -> None:
    meter = RateMeter()
    meter.add(1, 0.0)
    meter.add(1, 0.05)
    meter.add(1, 0.1)
    stats = meter.report()
    assert stats is not None
    assert format_rate(stats) == (
        "average rate: 20.000\n\tmin: 0.050s max: 0.050s std dev: 0.00000s window: 3"
    )
    table = rate_table([("/a", stats), ("/bb", stats)])
    assert table.splitlines()[0].split() == [
        "topic",
        "rate",
        "min_delta",
        "max_delta",
        "std_dev",
        "window",
    ]
    assert table.splitlines()[2].split()[-1] == "3" and table.splitlines()[3].split()[-1] == "3"
    assert table.endswith("3     \n\n")  # rostopic prints a table that ends in a newline


def test_bandwidth() -> None:
    meter = BandwidthMeter(window=100)
    assert meter.report() is None
    meter.add([1000, 3000], 10.0)
    bw = meter.report(now=12.0)
    assert bw is not None and bw.rate == pytest.approx(2000.0) and bw.mean == 2000
    assert (
        format_bandwidth(bw)
        == "average: 2.00KB/s\n\tmean: 2.00KB min: 1.00KB max: 3.00KB window: 2"
    )


def test_delay() -> None:
    meter = DelayMeter()
    meter.add([0.1, 0.3])
    stats = meter.report()
    assert (
        stats is not None and stats.value == pytest.approx(0.2) and stats.max == pytest.approx(0.3)
    )


def test_hz_average_survives_read_jitter_at_200khz() -> None:
    """A 200 kHz stream read every ~1 ms, each read up to 1 ms late, the last one 2 ms late.

    rostopic's 1/mean interval over 50,000 messages (a quarter of a second) is decided by the
    window's two ends and was 0.8% off here; the fit over the last 5 s is not.
    """
    rng = random.Random(7)
    rate, seconds = 200_000, 6.0
    meter = RateMeter(DEFAULT_WINDOW, DEFAULT_SPAN)
    sent = 0
    reads = int(seconds * 1000)
    for i in range(1, reads + 1):
        due = i / 1000
        late = 0.002 if i == reads else rng.uniform(0.0, 0.001)
        meter.add(int(due * rate) - sent, 100.0 + due + late)
        sent = int(due * rate)
    stats = meter.report()
    assert stats is not None
    assert stats.value == pytest.approx(rate, rel=0.002)
    assert stats.window > DEFAULT_WINDOW  # 5 s of messages, not 50,000
    assert stats.min >= 0 and stats.max < 0.002 / 100  # per-message intervals, spread per batch
