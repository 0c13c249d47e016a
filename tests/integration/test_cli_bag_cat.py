"""``bag cat`` (issue 15): NDJSON (or CSV) of the messages of bags, in time order."""

from __future__ import annotations

import base64
import json
from pathlib import Path
from types import SimpleNamespace

import pytest

from rostools.bag.tools.ops import convert
from tests.support.bagdata import read_stream, write_sample
from tests.support.env import CORPUS, needs_corpus, run_cli


def _lines(*args: str) -> list[dict[str, object]]:
    done = run_cli("bag", "cat", *args)
    assert done.returncode == 0, done.stderr
    return [json.loads(line) for line in done.stdout.splitlines()]


@needs_corpus
def test_cat_fields_match_the_mcap_library(tmp_path: Path) -> None:
    """topic, log_time, publish_time and sequence as the mcap library reads them; a decoded
    message wherever the type allows, with header.stamp as ``stamp``."""
    from mcap.reader import make_reader

    out = tmp_path / "example.mcap"
    convert(CORPUS / "ros1" / "roswire" / "example.bag", out)
    ours = _lines(str(out))
    with out.open("rb") as f:
        theirs = [
            {"topic": c.topic, "type": s.name if s else "", "log_time": m.log_time,
             "publish_time": m.publish_time, "sequence": m.sequence}
            for s, c, m in make_reader(f).iter_messages(log_time_order=True)
        ]  # fmt: skip
    keys = ("topic", "type", "log_time", "publish_time", "sequence")
    assert [{k: o[k] for k in keys} for o in ours] == theirs
    assert all(isinstance(o["msg"], dict) for o in ours)
    stamped = [o for o in ours if "stamp" in o]
    assert stamped and all(
        o["stamp"]
        == o["msg"]["header"]["stamp"]["secs"] * 10**9  # type: ignore[index]
        + o["msg"]["header"]["stamp"]["nsecs"]  # type: ignore[index]
        for o in stamped
    )


def test_cat_options_and_files_in_time_order(tmp_path: Path) -> None:
    a = write_sample(tmp_path / "a.bag", 40)
    b = write_sample(tmp_path / "b.mcap", 40)
    both = _lines(str(a.path), str(b.path), "/count")
    assert [o["log_time"] for o in both] == sorted(m[2] for m in a.stream * 2 if m[0] == "/count")
    assert "publish_time" not in both[0] and both[1]["publish_time"] == both[1]["log_time"]
    assert [o["msg"] for o in both[:2]] == [{"data": 2}, {"data": 2}]  # a.bag's first on a tie
    assert len(_lines(str(a.path), "-n", "5")) == 5
    window = _lines(str(a.path), "--start", "0.01", "--end", "0.02")
    assert window and all(10**7 <= int(str(o["log_time"])) <= 2 * 10**7 for o in window)
    kept = _lines(str(a.path), "--filter", "topic == '/point' and m.x > 30")
    assert [o["msg"]["x"] for o in kept] == [31.0, 35.0, 39.0]  # type: ignore[index]
    raw = _lines(str(a.path), "--raw", "-n", "3")
    assert [base64.b64decode(str(o["data"])) for o in raw] == [
        m[3] for m in read_stream(a.path)[:3]
    ]
    csv = run_cli("bag", "cat", str(a.path), "/point", "-F", "csv", "-n", "2").stdout.splitlines()
    assert csv[0] == "%time,field.x,field.y,field.z" and csv[1].startswith("3000009,3.0,-3.0,")
    many = run_cli("bag", "cat", str(a.path), "-F", "csv")
    assert many.returncode == 2 and "--format csv prints one topic" in many.stderr


@needs_corpus
def test_cat_decodes_ros2_cdr_through_rosbags() -> None:
    """rosbag2's talker: /topic carries "Hello, world! N"; /rosout's log lines say the same."""
    folder = CORPUS / "mcap" / "rosbag2"
    lines = _lines(str(folder / "rosbag2_py" / "talker" / "talker.mcap"), "/topic")
    assert [o["msg"] for o in lines] == [{"data": f"Hello, world! {i}"} for i in range(10)]
    assert lines[0]["type"] == "std_msgs/msg/String"
    log = _lines(str(folder / "rosbag2_py" / "talker" / "talker.mcap"), "/rosout", "-n", "1")
    assert log[0]["msg"]["msg"] == "Publishing: 'Hello, world! 0'"  # type: ignore[index]
    assert "INFO" not in log[0]["msg"]  # type: ignore[operator]  # a constant, not a field
    events = run_cli("bag", "cat", str(folder / "rosbag2_cpp" / "only_services.mcap"))
    assert events.returncode == 1 and "cannot read the ROS 2 type example_interfaces/srv/" in (
        events.stderr
    )
    assert len(events.stderr.strip().splitlines()) == 1


def test_a_message_that_does_not_decode_is_named(tmp_path: Path) -> None:
    from rostools.bag.formats.access import open_writer
    from tests.support.bagdata import STRING_MD5

    path = tmp_path / "bad.bag"
    with open_writer(path) as writer:
        conn = writer.add_connection("/bad", "std_msgs/String", STRING_MD5, "string data\n")
        writer.write(conn, 1, b"\x05\x00\x00\x00ab")  # says 5 bytes, holds 2
    done = run_cli("bag", "cat", str(path))
    assert done.returncode == 1 and done.stderr.count("\n") == 1
    assert f"{path}: /bad at 0.000000001 s: " in done.stderr


def test_lines_are_written_in_batches_bounded_by_size(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Big messages (images as base64) are written before 512 lines pile up in memory."""
    from rostools.cli.bag import cat

    a = write_sample(tmp_path / "a.bag", 40)
    monkeypatch.setattr(cat, "FLUSH_BYTES", 200)
    writes: list[str] = []
    monkeypatch.setattr("sys.stdout", SimpleNamespace(write=writes.append))
    cat.cat([str(a.path)], cat.CatFormat.json, True, None, None, None, None)
    lines = "".join(writes).splitlines()
    assert len(lines) == len(a.stream) and len(writes) >= len(lines) // 3
