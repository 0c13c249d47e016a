"""The file commands of ``rostools bag``: info, filter, convert, compress, decompress, recover."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
import yaml

from rostools.bag.formats import rosbag1_format as fmt
from rostools.bag.formats.access import bag_info, open_bag
from tests.support.bagdata import (
    STEP_NS,
    STRING_MD5,
    bag_records,
    read_stream,
    write_play_bag,
    write_sample,
)
from tests.support.env import run_cli


def test_info_text_json_yaml_and_freq(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "s.bag", 400, compression="bz2")
    text = run_cli("bag", "info", str(sample.path), "--freq")
    assert text.returncode == 0, text.stderr
    assert re.search(r"^compression:\s+bz2 \[1/1 chunks", text.stdout, re.M)
    assert re.search(r"/count\s+100 msgs @\s+250.0 Hz : std_msgs/Int32", text.stdout)
    assert "(2 connections)" in text.stdout
    data = json.loads(run_cli("bag", "info", str(sample.path), "-F", "json").stdout)
    assert data["messages"] == 400 and data["indexed"] is True
    assert {t["topic"]: t["messages"] for t in data["topics"]} == {
        "/chatter": 200,
        "/count": 100,
        "/point": 100,
    }
    # YAML is rosbag info -y's text: the same data, but version is a number there (2.0)
    as_yaml = run_cli("--format", "yaml", "bag", "info", str(sample.path)).stdout
    assert yaml.safe_load(as_yaml) == {**data, "version": 2.0}
    two = json.loads(
        run_cli("bag", "info", str(sample.path), str(sample.path), "-F", "json").stdout
    )
    assert two == [data, data]


def test_info_yaml_flag_and_keys(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "s.bag", 40)
    path = str(sample.path)
    data = yaml.safe_load(run_cli("bag", "info", "-y", path).stdout)
    assert data == {**json.loads(run_cli("bag", "info", path, "-F", "json").stdout), "version": 2.0}
    assert run_cli("bag", "info", "-k", "messages", path).stdout == "40\n"  # -k implies YAML
    assert run_cli("bag", "info", "-y", "-k", "topics[1].topic", path).stdout == "/count\n"
    assert yaml.safe_load(run_cli("bag", "info", "-k", "topics[-1]", path).stdout) == {
        "topic": "/point", "type": "geometry_msgs/Point", "messages": 10
    }  # fmt: skip
    assert (
        json.loads(run_cli("bag", "info", "-F", "json", "-k", "size", path, path).stdout)
        == [data["size"]] * 2
    )
    for key, words in [
        ("nope", "has no key 'nope' (keys here: path, version"),
        ("topics[7]", "has no key 'topics[7]' (3 entries here)"),
        ("topics..x", "bad key 'topics..x'"),
    ]:
        done = run_cli("bag", "info", "-k", key, path)
        assert done.returncode == 2 and done.stdout == ""
        assert done.stderr.count("\n") == 1 and words in done.stderr, done.stderr


def test_filter_by_expression_topics_and_time(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "s.bag", 400)
    out = tmp_path / "f.mcap"
    expr = 'topic == "/count" and m.data % 8 == 2 and t.to_sec() >= 0'
    done = run_cli("bag", "filter", str(sample.path), str(out), expr, "-F", "json")
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout.splitlines()[-1])["messages_written"] == 50
    kept = read_stream(out)
    assert [(topic, t) for topic, _, t, _ in kept] == [
        (topic, t)
        for topic, _, t, _ in sample.stream
        if topic == "/count" and (t // STEP_NS) % 8 == 2
    ]
    window = tmp_path / "w.bag"
    done = run_cli(
        "bag",
        "filter",
        str(sample.path),
        str(window),
        "-t",
        "/point",
        "--start",
        "0.1",
        "--end",
        "0.2",
    )
    assert done.returncode == 0, done.stderr
    times = [t for _, _, t, _ in read_stream(window)]
    assert times and all(0.1e9 <= t <= 0.2e9 for t in times)
    assert {topic for topic, *_ in read_stream(window)} == {"/point"}


@pytest.mark.parametrize(
    ("expr", "words"),
    [("m.nosuch", "failed on"), ("(", "filter expression '(' is not a Python expression")],
)
def test_filter_expression_errors_leave_no_output(tmp_path: Path, expr: str, words: str) -> None:
    sample = write_sample(tmp_path / "s.bag", 40)
    done = run_cli("bag", "filter", str(sample.path), str(tmp_path / "o.bag"), expr)
    assert done.returncode == 2 and words in done.stderr, done.stderr
    assert done.stderr.count("\n") == 1
    assert not (tmp_path / "o.bag").exists()


def test_convert_round_trip_and_refusals(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "s.bag", 500, compression="lz4")
    mcap = tmp_path / "s.mcap"
    back = tmp_path / "back.bag"
    for src, dst, extra in ((sample.path, mcap, ["-c", "lz4"]), (mcap, back, ["-c", "bz2"])):
        done = run_cli("bag", "convert", str(src), str(dst), *extra)
        assert done.returncode == 0, done.stderr
    assert read_stream(back) == read_stream(sample.path) == sample.stream
    assert bag_info(mcap).compression[0].compression == "lz4"
    assert bag_info(back).compression[0].compression == "bz2"
    again = run_cli("bag", "convert", str(sample.path), str(mcap))
    assert again.returncode == 2 and "exists" in again.stderr, again.stderr
    same = run_cli("bag", "convert", str(sample.path), str(sample.path))
    assert same.returncode == 2 and "same file" in same.stderr
    bad = run_cli("bag", "convert", str(sample.path), str(tmp_path / "x.mcap"), "-c", "bz2")
    assert bad.returncode == 2 and "bz2" in bad.stderr


def test_compress_and_decompress_in_place(tmp_path: Path) -> None:
    sample = write_sample(tmp_path / "s.bag", 300)
    done = run_cli("bag", "compress", "--lz4", str(sample.path))
    assert done.returncode == 0, done.stderr
    assert f"to {sample.path} " in done.stderr  # the final name, not a temporary one
    assert bag_info(sample.path).compression[0].compression == "lz4"
    assert bag_info(tmp_path / "s.orig.bag").compression[0].compression == "none"
    assert read_stream(sample.path) == sample.stream
    skipped = run_cli("bag", "decompress", str(sample.path))  # its backup is in the way
    assert skipped.returncode == 0 and skipped.stderr.startswith("Skipping "), skipped.stderr
    assert bag_info(sample.path).compression[0].compression == "lz4"  # left as it was
    done = run_cli("bag", "decompress", "-f", str(sample.path))
    assert done.returncode == 0, done.stderr
    assert bag_info(sample.path).compression[0].compression == "none"
    assert read_stream(sample.path) == sample.stream
    outdir = tmp_path / "out"
    outdir.mkdir()
    done = run_cli("bag", "compress", str(sample.path), "--output-dir", str(outdir))
    assert done.returncode == 0 and bag_info(outdir / "s.bag").compression[0].compression == "bz2"


def test_compressing_a_damaged_bag_keeps_what_reads_and_exits_6(tmp_path: Path) -> None:
    """Issue 24: the rest of the bag is compressed, the original kept, the loss named."""
    sample = write_sample(tmp_path / "s.bag", 400, chunk_size=3000)
    raw = sample.path.read_bytes()
    victim = [r for r in bag_records(raw) if r[1] == fmt.OP_CHUNK][2]
    (tmp_path / "d.bag").write_bytes(raw[: victim[0]] + bytes(8) + raw[victim[0] + 8 :])
    done = run_cli("bag", "compress", str(tmp_path / "d.bag"))
    assert done.returncode == 6, done.stderr
    errors = [line for line in done.stderr.splitlines() if line.startswith("rostools: ")]
    assert len(errors) == 1 and "compressed 1 bag" in errors[0] and str(victim[0]) in errors[0]
    assert (tmp_path / "d.orig.bag").read_bytes() == (
        raw[: victim[0]] + bytes(8) + raw[victim[0] + 8 :]
    )
    # An uncompressed chunk whose header is lost still reads: every message is there.
    assert read_stream(tmp_path / "d.bag") == sample.stream
    assert bag_info(tmp_path / "d.bag").compression[0].compression == "bz2"


def test_recover_reports_loss_with_exit_6(tmp_path: Path) -> None:
    sample = write_sample(
        tmp_path / "s.bag", 3000, compression="bz2", chunk_size=20_000, close=False
    )
    size = sample.path.stat().st_size
    cut = tmp_path / "cut.bag"
    cut.write_bytes(sample.path.read_bytes()[: size - 5000])  # inside the last chunk
    done = run_cli("bag", "recover", str(cut), "-F", "json")
    assert done.returncode == 6, done.stderr
    report = json.loads(done.stdout)
    assert report["lost"] and report["output"] == str(tmp_path / "cut.recovered.bag")
    recovered = read_stream(tmp_path / "cut.recovered.bag")
    assert 0 < len(recovered) < 3000 and recovered == sample.stream[: len(recovered)]


def test_reindex_takes_several_bags_in_place_as_rosbag(tmp_path: Path) -> None:
    """rosbag reindex A B: each rewritten in place, its original kept as A.orig.bag (issue 13)."""
    bags = [write_sample(tmp_path / f"{name}.bag", 300, close=False) for name in "ab"]
    originals = [b.path.read_bytes() for b in bags]
    done = run_cli("bag", "reindex", "-q", *[str(b.path) for b in bags])
    assert done.returncode == 0 and done.stderr == "", done.stderr
    for bag, original in zip(bags, originals, strict=True):
        assert read_stream(bag.path) == bag.stream
        assert bag.path.with_name(bag.path.stem + ".orig.bag").read_bytes() == original
    again = run_cli("bag", "reindex", str(bags[0].path))
    assert again.returncode == 0 and "a.orig.bag already exists" in again.stderr
    out = tmp_path / "out"
    out.mkdir()
    done = run_cli("bag", "reindex", "--output-dir", str(out), str(bags[1].path), "-F", "json")
    assert done.returncode == 0 and json.loads(done.stdout)["output"] == str(out / "b.bag")
    assert read_stream(out / "b.bag") == bags[1].stream


@pytest.mark.parametrize("out", ["cut.bag", "cut.mcap"])
def test_filter_latched_keeps_what_a_late_subscriber_had(tmp_path: Path, out: str) -> None:
    src = tmp_path / "p.bag"
    write_play_bag(src)  # /latched "old" (latched) at 100 s; /chatter m0..m9 from 100.0 s
    done = run_cli("bag", "filter", str(src), str(tmp_path / out), "--start", "0.45", "--latched")
    assert done.returncode == 0, done.stderr
    with open_bag(tmp_path / out) as reader:
        got = [(c.topic, t, bytes(d[4:]).decode(), c.latching) for c, t, d in reader.messages()]
    start = 100_450_000_000
    assert got[0] == ("/latched", start, "old", True)  # moved to the cut, still latched
    assert [g[2] for g in got[1:]] == ["m5", "m6", "m7", "m8", "m9"]
    plain = run_cli("bag", "filter", str(src), str(tmp_path / "plain.bag"), "--start", "0.45")
    assert plain.returncode == 0
    with open_bag(tmp_path / "plain.bag") as reader:
        assert [c.topic for c, _, _ in reader.messages()] == ["/chatter"] * 5


def test_convert_says_what_a_bag_cannot_hold(tmp_path: Path) -> None:
    from rostools.bag.formats import mcap_format as fmt
    from rostools.bag.formats.mcap_writer import McapWriter

    with McapWriter(tmp_path / "x.mcap") as writer:
        conn = writer.add_connection("/s", "std_msgs/String", STRING_MD5, "string data\n")
        writer.write(conn, 10, b"\x01\x00\x00\x00x")
        writer.add_extra(fmt.Metadata("robot", {"name": "r2"}))
    done = run_cli("bag", "convert", str(tmp_path / "x.mcap"), str(tmp_path / "x.bag"))
    assert done.returncode == 0, done.stderr
    assert "left out 1 MCAP attachment/metadata record: a .bag has no place for them" in (
        done.stderr
    )
    again = run_cli(
        "bag", "convert", str(tmp_path / "x.mcap"), str(tmp_path / "y.mcap"), "-F", "json"
    )
    assert json.loads(again.stdout.splitlines()[-1])["extras_copied"] == 1
    info = json.loads(run_cli("bag", "info", str(tmp_path / "y.mcap"), "-F", "json").stdout)
    assert (info["attachments"], info["metadata"]) == (0, 1)
    text = run_cli("bag", "info", str(tmp_path / "y.mcap")).stdout
    assert re.search(r"^metadata:\s+1$", text, re.M)
