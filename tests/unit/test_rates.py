"""Rate, bandwidth and delay statistics (rostopic's definitions)."""

from __future__ import annotations

import random
import statistics
import time

import pytest

from rostools.rates import (
    DEFAULT_SPAN,
    DEFAULT_WINDOW,
    Bandwidth,
    BandwidthMeter,
    DelayMeter,
    RateMeter,
    Stats,
    format_bandwidth,
    format_delay,
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


def _fitted_rate(points: list[tuple[int, float]]) -> float:
    """The least-squares rate through (message number, arrival) points, by the statistics module."""
    fit = statistics.linear_regression([c for c, _ in points], [t for _, t in points])
    return 1.0 / fit.slope


def test_an_explicit_window_holds_that_many_messages_whatever_one_read_brings() -> None:
    """`hz -w 10` is rostopic's window exactly, even when each read brings 100 messages."""
    meter = RateMeter(window=10)
    meter.add(1, 0.0)
    for second in range(1, 6):
        meter.add(100, float(second))
    stats = meter.report()
    assert stats is not None
    assert stats.window == 10
    assert stats.value == pytest.approx(100.0)
    assert stats.min == pytest.approx(0.01) and stats.max == pytest.approx(0.01)


def test_the_window_drops_the_oldest_intervals_even_part_of_a_batch() -> None:
    """Window 5 keeps the last 4 intervals: two of a 3-message batch, and the newest batch."""
    meter = RateMeter(window=5)
    meter.add(1, 0.0)
    meter.add(3, 3.0)  # three intervals of 1 s
    meter.add(2, 4.0)  # two of 0.5 s
    stats = meter.report()
    assert stats is not None
    assert stats.window == 5
    assert (stats.min, stats.max) == pytest.approx((0.5, 1.0))
    assert stats.std_dev == pytest.approx(statistics.pstdev([1.0, 1.0, 0.5, 0.5]))
    meter.add(2, 4.5)  # exactly the rest of the 1 s intervals leave
    stats = meter.report()
    assert stats is not None
    assert stats.window == 5
    assert (stats.min, stats.max) == pytest.approx((0.25, 0.5))


@pytest.mark.parametrize("window", [2, 3, 7])
def test_small_windows_are_rostopics(window: int) -> None:
    """-w N keeps N messages (N - 1 intervals), as rostopic hz and delay do."""
    meter = RateMeter(window=window)
    delays = DelayMeter(window=window)
    t = 0.0
    meter.add(1, t)
    steps = [0.5, 0.1, 0.3, 0.9, 0.2, 0.4, 0.6, 0.7]
    for step in steps:
        t += step
        meter.add(1, t)
    delays.add(steps)
    kept = steps[-(window - 1) :]
    for stats in (meter.report(), delays.report()):
        assert stats is not None
        assert stats.window == window
        assert stats.min == pytest.approx(min(kept)) and stats.max == pytest.approx(max(kept))
        assert stats.std_dev == pytest.approx(statistics.pstdev(kept), abs=1e-12)


def test_a_window_of_one_message_keeps_the_last_interval() -> None:
    """rostopic's -w 1 never reports; ours reports the last interval rather than nothing."""
    meter = RateMeter(window=1)
    for t in (0.0, 1.0, 1.5):
        meter.add(1, t)
    stats = meter.report()
    assert stats is not None and stats.window == 2 and stats.value == pytest.approx(2.0)


def test_the_rate_is_the_least_squares_fit_over_the_windows_batches() -> None:
    """Uneven batches: the slope through every batch in the window, not 1 / mean interval."""
    meter = RateMeter(window=6)
    arrivals = [(1, 0.0), (3, 0.010), (2, 0.013), (1, 0.020), (2, 0.031), (1, 0.034)]
    points, count = [], 0
    for batch, t in arrivals:
        meter.add(batch, t)
        count += batch
        points.append((count, t))
    stats = meter.report()
    assert stats is not None and stats.window == 6
    # the window is messages 5..10, so the batches that end at 6, 7, 9 and 10
    in_window = [(c, t) for c, t in points if c >= count - 5]
    assert stats.value == pytest.approx(_fitted_rate(in_window), rel=1e-9)
    mean_interval = (0.034 - 0.013) / 5  # what rostopic would give
    assert abs(stats.value - 1 / mean_interval) > 1.0


def test_three_batches_are_fitted_two_are_not() -> None:
    meter = RateMeter()
    meter.add(1, 0.0)
    meter.add(1, 1.0)
    meter.add(3, 2.0)
    stats = meter.report()
    assert stats is not None
    assert stats.value == pytest.approx(_fitted_rate([(1, 0.0), (2, 1.0), (5, 2.0)]))
    two = RateMeter()
    two.add(1, 0.0)
    two.add(3, 2.0)
    stats = two.report()
    assert stats is not None and stats.value == pytest.approx(1.5)  # 1 / mean interval


def _jittered_200khz(start: float) -> RateMeter:
    """Six seconds of a 200 kHz stream read every ~1 ms, each read up to 1 ms late."""
    rng = random.Random(7)
    rate = 200_000
    meter = RateMeter(DEFAULT_WINDOW, DEFAULT_SPAN)
    sent = 0
    for i in range(1, 6001):
        due = i / 1000
        meter.add(int(due * rate) - sent, start + due + rng.uniform(0.0, 0.001))
        sent = int(due * rate)
    return meter


def test_the_rate_is_as_exact_at_ros_times_as_near_zero() -> None:
    """Arrival times of the epoch's size (ROS time, 1.7e9 s) give the same average to the
    thousandth of a hertz hz prints."""
    near, far = _jittered_200khz(100.0).report(), _jittered_200khz(1.7e9).report()
    assert near is not None and far is not None
    assert abs(far.value - near.value) < 0.001


def test_a_last_report_before_any_message_is_nothing() -> None:
    """Ctrl-C before the first message asks for the last report: there is none."""
    assert RateMeter().report(again=True) is None
    assert DelayMeter().report(again=True) is None
    meter = RateMeter()
    meter.add(1, 3.0)  # one message: no interval yet
    assert meter.report(again=True) is None


def test_messages_of_one_instant_have_rate_zero() -> None:
    """A coarse clock gives every read the same time: rate 0, as rostopic's 1 / 0 guard."""
    meter = RateMeter()
    for _ in range(4):
        meter.add(2, 7.0)
    stats = meter.report()
    assert stats is not None
    assert (stats.value, stats.min, stats.max, stats.window) == (0.0, 0.0, 0.0, 8)


def test_a_first_batch_counts_its_messages_as_arriving_together() -> None:
    meter = RateMeter()
    meter.add(3, 10.0)
    meter.add(1, 11.0)
    stats = meter.report()
    assert stats is not None
    assert (stats.window, stats.min) == (4, 0.0) and stats.max == pytest.approx(1.0)
    assert stats.value == pytest.approx(3.0)  # 1 / mean of 0, 0 and 1 s


def test_reads_with_no_message_and_reads_at_the_same_time() -> None:
    """A read that brings nothing (a --filter dropped all) counts nothing; two reads at one
    clock reading are not time going backwards."""
    meter = RateMeter()
    assert meter.report() is None  # nothing yet
    meter.add(1, 0.0)
    meter.add(0, 0.5)
    meter.add(1, 1.0)
    meter.add(1, 1.0)
    stats = meter.report()
    assert stats is not None
    assert (stats.window, stats.min) == (3, 0.0) and stats.max == pytest.approx(1.0)


def test_time_going_back_reports_what_came_after() -> None:
    """Sim time restarted (a looping bag): the messages since are reported at once."""
    meter = RateMeter()
    meter.add(1, 5.0)
    meter.add(1, 6.0)
    assert meter.report() is not None
    meter.add(2, 1.0)
    stats = meter.report()
    assert stats is not None and stats.window == 2


def test_without_a_span_the_window_is_messages_only() -> None:
    meter = RateMeter(window=3)
    for i in range(20):
        meter.add(1, i * 0.001)
    stats = meter.report()
    assert stats is not None and stats.window == 3


def test_the_span_keeps_the_intervals_that_end_within_it() -> None:
    """min_span 2 s at one message a second: the last two intervals cover exactly 2 s."""
    meter = RateMeter(window=2, min_span=2.0)
    for i in range(11):
        meter.add(1, float(i))
    stats = meter.report()
    assert stats is not None and stats.window == 3


def test_delay_reports_once_per_new_message_and_again_on_request() -> None:
    meter = DelayMeter()
    assert meter.report() is None
    meter.add([0.25])
    stats = meter.report()
    assert stats is not None and stats.window == 2 and stats.value == pytest.approx(0.25)
    assert meter.report() is None  # nothing new
    meter.add([])
    assert meter.report() is None
    again = meter.report(again=True)  # Ctrl-C's last report
    assert again is not None and again.value == pytest.approx(0.25)
    meter.add([0.5])
    stats = meter.report()
    assert stats is not None and stats.window == 3


def test_delay_statistics() -> None:
    delays = [0.1, 0.4, 0.2, 0.9, 0.3]
    meter = DelayMeter()
    meter.add(delays)
    stats = meter.report()
    assert stats is not None
    assert stats.value == pytest.approx(statistics.fmean(delays))
    assert (stats.min, stats.max) == (0.1, 0.9)
    assert stats.std_dev == pytest.approx(statistics.pstdev(delays))
    assert stats.window == 6
    assert format_delay(stats) == (
        "average delay: 0.380\n\tmin: 0.100s max: 0.900s std dev: 0.27857s window: 6"
    )


def test_rate_std_dev_is_over_every_interval() -> None:
    meter = RateMeter()
    meter.add(1, 0.0)
    meter.add(1, 1.0)
    meter.add(1, 2.0)
    meter.add(2, 6.0)  # two intervals of 2 s
    stats = meter.report()
    assert stats is not None
    assert stats.std_dev == pytest.approx(statistics.pstdev([1.0, 1.0, 2.0, 2.0]))


def test_bandwidth_window_is_the_last_messages() -> None:
    """rostopic bw: sizes and the span from the oldest message in the window until now."""
    meter = BandwidthMeter(window=3)
    for i, size in enumerate([100, 200, 300, 400, 500]):
        meter.add([size], 10.0 + i)
    bw = meter.report(now=15.0)
    assert bw is not None
    assert bw.window == 3 and (bw.min, bw.max, bw.mean) == (300.0, 500.0, 400.0)
    assert bw.rate == pytest.approx(1200 / 3.0)  # since the message at 12 s
    default = BandwidthMeter()
    default.add([1] * 150, 1.0)
    bw = default.report(now=2.0)
    assert bw is not None and bw.window == 100  # rostopic bw's default window


def test_bandwidth_spans() -> None:
    meter = BandwidthMeter()
    meter.add([10, 20], 5.0)
    bw = meter.report(now=5.0)  # no time has passed: no rate, and no division by zero
    assert bw is not None and bw.rate == 0.0
    bw = meter.report(now=5.5)
    assert bw is not None and bw.rate == pytest.approx(60.0)


def test_bandwidth_reads_the_monotonic_clock_by_default() -> None:
    meter = BandwidthMeter()
    meter.add([500, 500], time.monotonic() - 1.0)
    bw = meter.report()
    assert bw is not None and 0 < bw.rate <= 1000.0


@pytest.mark.parametrize(
    ("rate", "text"),
    [
        (999.0, "average: 999.00B/s\n\tmean: 500.00B min: 2.00B max: 1500.00B window: 7"),
        (1000.0, "average: 1.00KB/s\n\tmean: 0.50KB min: 0.00KB max: 1.50KB window: 7"),
        (999_999.0, "average: 1000.00KB/s\n\tmean: 0.50KB min: 0.00KB max: 1.50KB window: 7"),
        (1e6, "average: 1.00MB/s\n\tmean: 0.00MB min: 0.00MB max: 0.00MB window: 7"),
        (25.5e6, "average: 25.50MB/s\n\tmean: 0.00MB min: 0.00MB max: 0.00MB window: 7"),
        # no unit past MB
        (
            12_345_678_900.0,
            "average: 12345.68MB/s\n\tmean: 0.00MB min: 0.00MB max: 0.00MB window: 7",
        ),
    ],
)
def test_bandwidth_units_are_rostopics(rate: float, text: str) -> None:
    """1000-based units chosen by the rate, and used for the sizes too."""
    assert format_bandwidth(Bandwidth(rate, 500.0, 2.0, 1500.0, 7)) == text


def test_rate_table_rule_is_as_wide_as_its_header() -> None:
    stats = Stats(1234.5678, 0.0001, 0.25, 0.00123, 50000)
    lines = rate_table([("/a_long_topic_name", stats), ("/b", stats)]).splitlines()
    assert lines[1] == "=" * len(lines[0])
    assert lines[2].startswith("/a_long_topic_name   1.235e+03   0.0001      0.25 ")
