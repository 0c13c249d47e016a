"""hz, bw and delay print the window once more when Ctrl-C stops them, as rostopic does."""

from __future__ import annotations

import signal

import pytest

from tests.support.procs import start_cli

FIRST = {"hz": "average rate", "bw": "average:", "delay": "average delay"}


@pytest.mark.parametrize("meter", ["hz", "bw", "delay"])
def test_ctrl_c_prints_a_last_report(
    rostools_master: str, cli_env: dict[str, str], meter: str
) -> None:
    pub = start_cli(
        "topic",
        "pub",
        "-r",
        "50",
        "/p",
        "geometry_msgs/PointStamped",
        "{header: auto}",
        env=cli_env,
    )
    rate = start_cli("topic", meter, "/p", env=cli_env)
    try:
        rate.expect(FIRST[meter], 20)  # the first report; the next is due a second later
        rate.signal(signal.SIGINT)
        rate.expect(FIRST[meter], 5)  # at once, not a second later
        assert rate.popen.wait(10) == 0
    finally:
        rate.stop()
        pub.stop()
