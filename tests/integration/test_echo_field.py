"""A field that a published topic's type does not have is a usage error at once (exit 2).

``topic echo /chatter/dat`` on a std_msgs/String topic warned that the topic did not appear
to be published yet, then waited forever.
"""

from __future__ import annotations

import time

import pytest

from tests.support.env import run_cli
from tests.support.load import scaled
from tests.support.procs import start_cli, wait_for


@pytest.mark.parametrize("verb", ["echo", "plot"])
def test_a_misspelt_field_is_exit_2_at_once(
    rostools_master: str, cli_env: dict[str, str], verb: str
) -> None:
    pub = start_cli("topic", "pub", "/chatter", "std_msgs/String", "hi", env=cli_env)
    try:
        wait_for(lambda: "/chatter" in run_cli("topic", "list", env=cli_env).stdout, 15, "pub")
        started = time.monotonic()
        done = run_cli("topic", verb, "/chatter/dat", "--timeout", "300", env=cli_env)
        assert time.monotonic() - started < scaled(15)  # not the 300 s it was given
    finally:
        pub.stop()
    assert done.returncode == 2, done.stderr
    assert done.stderr.startswith("rostools: /chatter/dat: /chatter is std_msgs/String: "), (
        done.stderr
    )
    assert "dat" in done.stderr.splitlines()[-1]
