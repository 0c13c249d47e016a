"""Hostile command-line and YAML input: one line, exit 2, at once (issue 11's cases)."""

from __future__ import annotations

import time
from pathlib import Path

import pytest

from tests.support.env import CORPUS, needs_corpus, run_cli
from tests.support.load import scaled
from tests.unit.test_yamlio import BOMB

DEEP = "[" * 10_000 + "]" * 10_000


@pytest.mark.parametrize(
    ("args", "said"),
    [
        (["param", "load", "{tmp}/bomb.yaml"], "it expands to more than 1,000,000 values"),
        (["param", "set", "/x", DEEP], "nested deeper than 100 levels"),
        (["param", "set", "/x", "{a: 1"], "(line 2, column 1)"),
        (["topic", "pub", "-1", "/x", "std_msgs/String", DEEP], "nested deeper"),
        (["topic", "pub", "-1", "/x", "std_msgs/Int32", "data: " + "1" * 10_000], "too long"),
        (["topic", "pub", "-1", "/x", "std_msgs/String", "-f", "{tmp}/latin1.yaml"], "not UTF-8"),
        (["topic", "pub", "-r", "nan", "/x", "std_msgs/Empty", "{}"], "not a finite number"),
        (["bag", "play", "{tmp}/bomb.yaml", "-r", "inf"], "not a finite number"),
        (["param", "set", "--", "-x", "3"], "'-x' is not a legal ROS name"),  # was set
        (["param", "set", "--verbos", "5"], "no such option: --verbos"),  # was /--verbos
        (["topic", "pub", "-1", "-x", "/x", "std_msgs/String", "a"], "no such option: -x"),
        (["topic", "echo", "/a b"], "'/a b' is not a legal ROS name"),
        (["node", "info", "a//b"], "not a legal ROS name"),
        (["service", "call", "/s:x"], "not a legal ROS name"),
        (["param", "set", "/x", "- - - -"], "/x[0][0][0][0]: null is not a parameter value"),
        # a YAML date was an internal error (cannot marshal datetime.date)
        (["param", "set", "/x", "2024-01-01"], "/x: 2024-01-01 is a YAML timestamp, not a"),
        (["param", "set", "/x", "{a: [2024-01-01 10:00:00]}"], "/x/a[0]: 2024-01-01 10:00:00"),
        (["param", "set", "/x", '{"\\n": null}'], "/x/\\n: null"),  # escaped, still one line
        (["param", "set", "/", '{"\\u0085": null}'], "rostools: /\\x85: null"),  # NEL too
        (["bag", "snapshot", "-O", "x.bag"], "give topics to buffer, or -a, -e REGEX, --topic-"),
        (["bag", "trigger", "--continue", "--after", "5"], "it takes no --after"),
    ],
)
def test_bad_input_is_one_line(
    args: list[str], said: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    (tmp_path / "bomb.yaml").write_text(BOMB)
    (tmp_path / "latin1.yaml").write_bytes(b"data: caf\xe9\n")
    began = time.monotonic()
    done = run_cli(*(a.replace("{tmp}", str(tmp_path)) for a in args), env=cli_env, timeout=30)
    assert done.returncode == 2, done.stderr
    assert said in done.stderr and len(done.stderr.splitlines()) == 1, done.stderr
    assert "Traceback" not in done.stderr and "internal error" not in done.stderr
    assert time.monotonic() - began < scaled(10)


@needs_corpus
@pytest.mark.parametrize(
    ("flip", "code", "said"),
    [
        (5036, 1, "message at 1550219983.835047007 s: a message on /text does not decode as"),
        (5379, 1, "message at 1550219977.520894051 s: std_msgs/Int32: line 1:"),
        # A record that does not parse is skipped, the rest printed, and exit 6 (issue 24).
        (4662, 6, "chunk at 4117: 50 bytes at offset 462 do not parse (record header at 4628:"),
    ],
)
def test_a_damaged_bag_says_where(
    flip: int, code: int, said: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    """One flipped byte: the error names the file and the message or record (issue 11)."""
    data = bytearray((CORPUS / "ros1/ros_comm/rosbag_storage_test.bag").read_bytes())
    data[flip] ^= 0xFF
    bag = tmp_path / "damaged.bag"
    bag.write_bytes(data)
    done = run_cli("topic", "echo", "-b", str(bag), "-a", "-F", "json", env=cli_env)
    assert done.returncode == code, done.stderr
    errors = [line for line in done.stderr.splitlines() if line.startswith("rostools: ")]
    assert len(errors) == 1 and f"{bag}: {said}" in errors[0], done.stderr
    assert all(line.startswith(("rostools: ", "note: ")) for line in done.stderr.splitlines())
