"""``tf frames``, ``tf monitor`` and ``tf pub`` on rostools core: what each says and its exit
code, bad input included (the peers' comparisons are in tests/interop/test_tf_tools_interop.py).
"""

from __future__ import annotations

import json
import signal
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.support.bagdata import write_sample
from tests.support.env import CORPUS, needs_corpus, run_cli
from tests.support.load import scaled
from tests.support.procs import Proc, publishers, start_cli, wait_for

TURTLES = CORPUS / "ros1" / "rosbag.js" / "example.bag"


@pytest.fixture
def two_pubs(rostools_master: str, cli_env: dict[str, str]) -> Iterator[list[Proc]]:
    """Two ``tf pub`` for two children of one parent, both registered."""
    procs = [
        start_cli("tf", "pub", "1", "0", "0", "0", "0", "0", "base", "left", env=cli_env),
        start_cli("tf", "pub", "0", "1", "0", "0", "0", "0", "1", "base", "right", env=cli_env),
    ]
    try:
        wait_for(lambda: len(publishers(rostools_master, "/tf_static")) == 2, 20, "both")
        yield procs
    finally:
        for proc in procs:
            proc.stop()


def test_two_tf_pubs_stay_visible_together(two_pubs: list[Proc], cli_env: dict[str, str]) -> None:
    done = run_cli("tf", "frames", "-w", "1", "-F", "json", env=cli_env)
    assert done.returncode == 0, done.stderr
    tree = json.loads(done.stdout)
    assert tree["frames"] == ["base", "left", "right"]
    assert [(e["parent"], e["child"], e["static"]) for e in tree["edges"]] == [
        ("base", "left", True),
        ("base", "right", True),
    ]
    text = run_cli("tf", "frames", "-w", "1", env=cli_env)
    assert text.stdout.splitlines()[0] == "base", text.stderr
    assert text.stdout.splitlines()[2].startswith("└── right  [/static_transform_publisher_")


def test_tf_pub_ends_cleanly_on_sigterm(two_pubs: list[Proc], rostools_master: str) -> None:
    left, _ = two_pubs
    left.signal(signal.SIGTERM)
    assert left.popen.wait(scaled(30)) == 0, left.output()
    wait_for(lambda: len(publishers(rostools_master, "/tf_static")) == 1, 15, "unregistered")


def test_tf_monitor_lists_each_static_broadcaster(
    two_pubs: list[Proc], cli_env: dict[str, str]
) -> None:
    done = run_cli("tf", "monitor", "-n", "1", env=cli_env)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[:3] == ["RESULTS: for all Frames", "", "Frames:"]
    assert sum(line.endswith("(static) Average Delay: 0 Max Delay: 0") for line in lines) == 2
    chain = run_cli("tf", "monitor", "left", "/right", "-n", "1", env=cli_env)
    assert chain.returncode == 0, chain.stderr
    assert "Chain is: left -> base -> right" in chain.stdout


def test_tf_frames_with_nothing_heard_is_not_found(
    rostools_master: str, cli_env: dict[str, str]
) -> None:
    done = run_cli("tf", "frames", "-w", "0.5", env=cli_env)
    assert done.returncode == 3
    assert done.stderr.strip() == "rostools: no tf data received within 0.5 s"


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["frames", "-o", "x.txt"], "cannot tell the format from the name"),
        (["frames", "-w", "0"], "--wait must be a number of seconds above 0"),
        (["monitor", "base"], "no frame or two"),
        (["monitor", "-n", "0"], "-n must be at least 1"),
        (["pub", "1", "2", "3"], "8 or 9 arguments, not 3"),
        (["pub", "-1", "0", "0", "0", "0", "0", "a", "a"], "are the same (a, a)"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(
    args: list[str], words: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    done = run_cli("tf", *args, env=cli_env, cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    assert len(done.stderr.strip().splitlines()) == 1 and words in done.stderr
    assert not list(tmp_path.iterdir())  # nothing written


def test_a_bag_without_tf_is_not_found(cli_env: dict[str, str], tmp_path: Path) -> None:
    write_sample(tmp_path / "sample.bag", 10)
    for verb in ("frames", "monitor"):
        done = run_cli("tf", verb, "-b", str(tmp_path / "sample.bag"), env=cli_env)
        assert done.returncode == 3, done.stderr
        assert "holds no /tf or /tf_static" in done.stderr


@needs_corpus
def test_a_bags_tree_as_text_dot_and_picture(cli_env: dict[str, str], tmp_path: Path) -> None:
    text = run_cli("tf", "frames", "-b", str(TURTLES), env=cli_env)
    assert text.returncode == 0, text.stderr
    lines = text.stdout.splitlines()
    assert lines[0] == "world"
    assert lines[1].startswith("├── turtle1  [/turtle1_tf_broadcaster, ")
    assert lines[2].startswith("│   └── carrot  [/static_transform_publisher_")
    assert lines[3].startswith("└── turtle2  [/turtle2_tf_broadcaster, ")
    dot = run_cli("tf", "frames", "-b", str(TURTLES), "-o", str(tmp_path / "t.dot"), env=cli_env)
    assert dot.returncode == 0, dot.stderr
    assert (
        '"world" -> "turtle1" [label="Broadcaster: /turtle1_tf_broadcaster\\n'
        in (tmp_path / "t.dot").read_text()
    )
    mon = run_cli("tf", "monitor", "-b", str(TURTLES), "-F", "json", env=cli_env)
    assert mon.returncode == 0, mon.stderr
    report = json.loads(mon.stdout)
    rates = {b["broadcaster"]: b["rate"] for b in report["broadcasters"]}
    assert rates["/turtle1_tf_broadcaster"] > 1
