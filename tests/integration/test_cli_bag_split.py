"""``bag split`` (issue 15): parts by count, duration, size or times; merge(split(x)) == x."""

from __future__ import annotations

import json
import subprocess
from pathlib import Path

import pytest

from tests.support.bagdata import STEP_NS, read_stream, write_sample
from tests.support.env import needs_ros1, run_cli, run_system_python


def _parts(done: subprocess.CompletedProcess[str]) -> list[dict[str, int | str]]:
    assert done.returncode == 0, done.stderr
    parts: list[dict[str, int | str]] = json.loads(done.stdout.splitlines()[-1])["parts"]
    return parts


@pytest.mark.parametrize("suffix", ["bag", "mcap"])
def test_merge_of_split_is_the_bag(tmp_path: Path, suffix: str) -> None:
    sample = write_sample(tmp_path / f"s.{suffix}", 400)
    parts = _parts(run_cli("bag", "split", str(sample.path), "--count", "70", "-F", "json"))
    assert [p["messages"] for p in parts] == [70] * 5 + [50]
    assert [Path(str(p["path"])).name for p in parts] == [f"s_{i}.{suffix}" for i in range(6)]
    merged = tmp_path / f"m.{suffix}"
    done = run_cli("bag", "merge", str(merged), *(str(p["path"]) for p in parts), "-q")
    assert done.returncode == 0, done.stderr
    assert read_stream(merged) == sample.stream  # message for message, in order


def test_duration_and_at(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "s.bag", 400)  # 400 messages, STEP_NS apart
    src = str(sample.path)
    out = str(tmp_path / "d.mcap")
    by_time = _parts(run_cli("bag", "split", src, "--duration", "0.1", "-o", out, "-F", "json"))
    per_part = round(0.1e9 / STEP_NS)  # messages in 0.1 s of bag time
    assert by_time[0]["messages"] in (per_part, per_part + 1) and len(by_time) == 4
    assert all(int(p["end"]) - int(p["start"]) < 100_000_000 for p in by_time)
    at = _parts(run_cli("bag", "split", src, "--at", "0.05,0.3", "-o", str(tmp_path / "a.bag"),
                        "-F", "json"))  # fmt: skip
    assert len(at) == 3 and int(at[1]["start"]) >= 50_000_000 and int(at[2]["start"]) >= 3e8
    assert sum(int(p["messages"]) for p in at) == 400
    rules = run_cli("bag", "split", src, "--count", "5", "--size", "1")
    assert rules.returncode == 2 and "give one of --duration, --size, --count or --at" in (
        rules.stderr
    )


def test_repeat_latched_starts_each_part_with_them(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "s.bag", 40)  # /chatter from /talker is latched
    parts = _parts(run_cli("bag", "split", str(sample.path), "--count", "10", "--repeat-latched",
                           "-F", "json"))  # fmt: skip
    latched = [m for m in sample.stream if m[1] == "/talker"]
    for i, part in enumerate(parts[1:], 1):
        first = read_stream(Path(str(part["path"])))[0]
        last_before = [m for m in latched if m[2] < int(part["start"])][-1]
        assert first[:2] == ("/chatter", "/talker") and first[3] == last_before[3], i


@needs_ros1
def test_rosbag_reads_every_part(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "s.bag", 200)
    parts = _parts(run_cli("bag", "split", str(sample.path), "--count", "64", "-F", "json"))
    script = (
        "import rosbag, sys\nprint(sum(rosbag.Bag(p).get_message_count() for p in sys.argv[1:]))\n"
    )
    stdout = run_system_python(script, *(str(p["path"]) for p in parts))
    assert stdout.strip() == "200"


def test_size_cuts_after_the_part_is_full(tmp_path: Path) -> None:
    from rostools.bag.tools.split import Cut, split

    sample = write_sample(tmp_path / "s.bag", 400)
    report = split(sample.path, tmp_path / "z.bag", Cut(size=4000))
    sizes = [sum(len(m[3]) for m in read_stream(p.path)) for p in report.parts]
    assert all(s >= 4000 for s in sizes[:-1]) and sum(p.messages for p in report.parts) == 400
    assert all(s - 4000 < 250 for s in sizes[:-1])  # cut at the first message past the size
