"""``topic plot`` against a live rospy publisher: the numbers plotted are the numbers sent,
and a terminal shows the axes and the series as they come."""

from __future__ import annotations

import json
import re
import sys
from collections.abc import Iterator

import pytest

from tests.support.env import needs_ros1, run_cli
from tests.support.procs import core_and_env, ros_env, start_ros1_node, wait_for

pytestmark = [pytest.mark.interop, needs_ros1]

ANSI = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]")


@pytest.fixture(scope="module")
def publisher(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, str]]:
    """Our master and plot_pub.py (rospy) publishing /odom and /scan at 50 Hz; the CLI's env."""

    tmp = tmp_path_factory.mktemp("plot")
    core, env = core_and_env(tmp)
    uri = env["ROS_MASTER_URI"]
    node = start_ros1_node("plot_pub.py", ["50"], ros_env(uri, tmp / "ros_home"))
    try:
        wait_for(lambda: "/scan" in run_cli("topic", "list", env=env).stdout, 20, "plot_pub")
        yield env
    finally:
        node.stop()
        core.stop()


def test_plotted_values_are_the_published_ones(publisher: dict[str, str]) -> None:
    """Two topics, a slice, header.stamp as x: every sample is what rospy sent, none lost.

    The stamps are a second apart, so the window that keeps them all is an hour."""
    done = run_cli(
        "topic", "plot", "/odom/pose/pose/position/x", "/scan/ranges[1:3]", "--stamp",
        "-n", "60", "--window", "1h", "-F", "json", "--timeout", "20", env=publisher, timeout=40,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    series = {r["series"]: r for r in map(json.loads, done.stdout.splitlines())}
    assert set(series) == {"/odom/pose/pose/position/x", "/scan/ranges[1]", "/scan/ranges[2]"}
    assert all(r["time"] == "header.stamp" for r in series.values())
    odom = series["/odom/pose/pose/position/x"]
    ks = [t - 1000 for t in odom["t"]]
    assert all(k == int(k) for k in ks) and ks == list(range(int(ks[0]), int(ks[0]) + len(ks)))
    assert odom["value"] == [k / 2 for k in ks]
    for i in (1, 2):
        scan = series[f"/scan/ranges[{i}]"]
        assert scan["value"] == [t - 1000 + i for t in scan["t"]]
    assert len(odom["t"]) + len(series["/scan/ranges[1]"]["t"]) == 60  # -n counts messages


def test_terminal_shows_axes_and_series_live(publisher: dict[str, str]) -> None:
    """In a terminal the plot is redrawn about ten times a second, and the last frame stays."""
    import pexpect

    child = pexpect.spawn(
        sys.executable,
        ["-m", "rostools", "topic", "plot", "/odom/pose/pose/position/x", "/scan/ranges[0]",
         "--window", "5s", "--timeout", "2.5"],
        env=publisher, encoding="utf-8", dimensions=(24, 90), timeout=30,
    )  # fmt: skip
    try:
        child.expect(pexpect.EOF)
    finally:
        child.close(force=True)
    assert child.exitstatus == 0, child.before
    screen = child.before
    assert screen.count("\x1b[H") >= 12  # frames drawn in place, on the alternate screen
    last = ANSI.sub("", screen.rpartition("\x1b[?1049l")[2]).replace("\r", "")
    lines = last.splitlines()
    assert 20 <= len(lines) <= 24 and max(map(len, lines)) <= 90, last
    assert "topic plot, last 5 s" in lines[0]
    assert "┌" in last and "└" in last and "┤" in last and "┬" in last  # both axes, with ticks
    assert "/odom/pose/pose/position/x" in last and "/scan/ranges[0]" in last  # the legend
    assert re.search(r"seconds since \d\d:\d\d:\d\d \(receive time\)", last)
    assert re.search(r"^\d+ messages, \d+/s$", lines[-1])
    assert re.search("[\u2801-\u28ff]", last)  # the lines themselves, in braille


def test_field_that_is_not_a_number(publisher: dict[str, str]) -> None:
    done = run_cli("topic", "plot", "/odom/header/frame_id", "-n", "1", env=publisher)
    assert done.returncode == 2
    assert done.stderr.startswith("rostools: /odom/header/frame_id is a string, not a number (")
    assert done.stderr.count("\n") == 1
