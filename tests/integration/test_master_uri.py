"""A malformed ROS_MASTER_URI (or --master-uri) is a usage error that says what is wrong.

``127.0.0.1:11411`` was read as port 80 of localhost ("connection refused", although a
master ran at that address), and ``htp://`` was taken for ``http://`` without a word.
"""

from __future__ import annotations

import pytest

from tests.support.env import run_cli


@pytest.mark.parametrize(
    ("uri", "problem", "hint"),
    [
        ("127.0.0.1:11411", "has no scheme", "write it as http://127.0.0.1:11411"),
        ("htp://localhost:11311", "has the scheme 'htp'; a ROS master speaks http",
         "write it as http://localhost:11311"),
        ("http://:11311", "has no host", "write it as http://HOST:PORT"),
        ("http://localhost:port/", "has a port that is not a number ('port')",
         "write it as http://HOST:PORT"),
    ],
)  # fmt: skip
@pytest.mark.parametrize(
    "argv", [["topic", "list"], ["param", "get", "/x"], ["topic", "echo", "/x"]], ids=" ".join
)
def test_a_malformed_master_uri_is_a_usage_error(
    cli_env: dict[str, str], uri: str, problem: str, hint: str, argv: list[str]
) -> None:
    cli_env["ROS_MASTER_URI"] = uri
    done = run_cli(*argv, env=cli_env, timeout=30)
    assert (done.returncode, done.stdout) == (2, "")
    assert done.stderr == f"rostools: ROS_MASTER_URI={uri} {problem} (hint: {hint})\n"


def test_the_option_is_checked_too(cli_env: dict[str, str]) -> None:
    done = run_cli("--master-uri", "localhost:11311", "topic", "list", env=cli_env)
    assert done.returncode == 2
    assert done.stderr.startswith("rostools: --master-uri=localhost:11311 has no scheme")
