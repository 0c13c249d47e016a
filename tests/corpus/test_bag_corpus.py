"""Third-party bags and MCAP files (../shared/corpus): our readers against the real rosbag,
the MCAP conformance suite's expected output, and rosbag2's own counts."""

from __future__ import annotations

import json
import re
import subprocess
from pathlib import Path
from typing import Any

import pytest
import yaml

from rostools.bag.formats import mcap_format
from rostools.bag.formats.access import bag_info, open_bag, topic_frequencies
from rostools.bag.formats.mcap_reader import McapReader
from rostools.bag.formats.model import BagFormatError
from rostools.bag.tools.recover import recover
from rostools.errors import RostoolsError
from tests.support.bagdata import digest
from tests.support.env import CORPUS, SYSTEM_PYTHON, needs_corpus, needs_ros1, run_cli

pytestmark = needs_corpus

ROS1 = CORPUS / "ros1"
NOT_BAGS = {
    "rosbag.js/empty-file.bag": "empty",
    "rosbag.js/asci-file.txt": "neither",
    "rosbag2/test.bag": "SQLite",
    "rosbag-rs/dummy.bag": "unindexed",
    "webviz/invalid.bag": "cut short",
}
UNSORTED = "rosbag.js/example-unsorted-chunks.bag"
#: Cut-short copies and the bags they were cut from (corpus README, MANIFEST.tsv).
DERIVED = {
    "embag_test_cut_at_index_pos.bag": "embag/test.bag",
    "example_cut_at_index_pos.bag": "rosbag.js/example.bag",
    "test1_cut_at_60pct.bag": "robot_localization/test1.bag",
}


def bags() -> list[str]:
    if not ROS1.is_dir():
        return []
    names = sorted(str(p.relative_to(ROS1)) for p in ROS1.rglob("*") if p.is_file())
    return [n for n in names if n not in NOT_BAGS]


def ours(path: Path) -> list[list[Any]]:
    with open_bag(path) as reader:
        return [[c.topic, t, digest(bytes(d))] for c, t, d in reader.messages()]


@pytest.fixture(scope="module")
def rosbag_view() -> dict[str, Any]:
    """What the real rosbag.Bag reads from every corpus bag, in one system-python run."""
    dump = Path(__file__).parent.parent / "support" / "rosbag_dump.py"
    paths = [str(ROS1 / name) for name in bags()]
    proc = subprocess.run(
        [SYSTEM_PYTHON, str(dump), *paths], capture_output=True, text=True, timeout=600, check=True
    )
    return {str(Path(k).relative_to(ROS1)): v for k, v in json.loads(proc.stdout).items()}


@needs_ros1
@pytest.mark.parametrize("name", bags())
def test_stream_matches_rosbag(name: str, rosbag_view: dict[str, Any]) -> None:
    theirs = rosbag_view[name]
    assert "error" not in theirs, theirs
    expected = theirs["stream"]
    if name == UNSORTED:
        # rosbag yields this bag in chunk order (2 s, 3 s, 1 s); we yield time order.
        expected = sorted(expected, key=lambda m: m[1])
    assert ours(ROS1 / name) == expected
    with open_bag(ROS1 / name) as reader:
        assert reader.indexed
        mine = [[c.topic, c.header()] for c in sorted(reader.connections, key=lambda c: c.id)]
    assert mine == [[topic, header] for topic, header in theirs["headers"]]


@needs_ros1
@pytest.mark.parametrize("name", bags())
def test_info_matches_rosbag_info(name: str, rosbag_view: dict[str, Any]) -> None:
    theirs = rosbag_view[name]["info"]
    info = bag_info(ROS1 / name)
    assert info.size == theirs["size"]
    if "messages" not in theirs:  # rosbag shows almost nothing for a bag without messages
        assert info.message_count == 0
        return
    assert info.message_count == theirs["messages"]
    if name != UNSORTED:  # rosbag takes start/end from the first/last chunk in file order
        assert round(info.start_ns / 1e9, 6) == pytest.approx(theirs["start"], abs=2e-6)
        assert round(info.end_ns / 1e9, 6) == pytest.approx(theirs["end"], abs=2e-6)
    assert info.compression[0].compression == theirs["compression"]
    if "uncompressed" in theirs:
        assert info.uncompressed_size == theirs["uncompressed"]
        assert info.compressed_size == theirs["compressed"]
    assert dict(info.types) == {t["type"]: t["md5"] for t in theirs["types"]}
    rows = [
        {"topic": t.topic, "type": t.type, "messages": t.messages, "connections": t.connections}
        for t in info.topics
    ]
    expected = [
        {"connections": 1, **{k: v for k, v in t.items() if k != "frequency"}}
        for t in theirs["topics"]
    ]
    assert rows == expected
    if name == UNSORTED:
        return  # rosbag's rates come from its chunk-order stream here
    with open_bag(ROS1 / name) as reader:
        rates = topic_frequencies(reader)
    # rosbag takes gaps between float seconds (~0.2 us steps at today's epoch); we use ns.
    assert rates == pytest.approx(
        {t["topic"]: t["frequency"] for t in theirs["topics"] if "frequency" in t}, rel=1e-2
    )


@needs_ros1
def test_info_text_is_rosbag_infos() -> None:
    """``bag info`` prints what ``rosbag info`` prints, byte for byte, for every corpus bag.

    Left out: the unsorted bag, whose start and end rosbag takes from chunk order (it prints a
    negative duration).
    """
    names = [n for n in bags() if n != UNSORTED]
    theirs = subprocess.run(
        ["rosbag", "info", *names], cwd=ROS1, capture_output=True, text=True, timeout=600
    )
    mine = run_cli("bag", "info", *names, cwd=ROS1, timeout=600)
    assert theirs.returncode == 0 == mine.returncode, mine.stderr
    assert mine.stdout.split("\n---\n") == theirs.stdout.split("\n---\n")


@needs_ros1
@pytest.mark.parametrize(
    "key",
    ["duration", "messages", "compression", "topics[0].topic", "types[0].md5", "version",
     "indexed", "start", "end", "size", "topics", "types"],
)  # fmt: skip
def test_info_keys_are_rosbag_infos(key: str) -> None:
    """``bag info -y -k KEY`` gives rosbag's value for every corpus bag that has topics."""
    names = [n for n in bags() if n != UNSORTED and bag_info(ROS1 / n).topics]
    theirs = subprocess.run(
        ["rosbag", "info", "-y", "-k", key, *names],
        cwd=ROS1, capture_output=True, text=True, timeout=600, check=True,
    )  # fmt: skip
    mine = run_cli("bag", "info", "-y", "-k", key, *names, cwd=ROS1, timeout=600)
    assert mine.returncode == 0, mine.stderr
    # duration: rosbag subtracts float seconds and prints 6 decimals; so do we (we gave 9).
    # Byte for byte: the documents, their '---' and the scalars as rosbag prints them.
    assert mine.stdout == theirs.stdout


@needs_ros1
def test_filter_print_is_rosbag_filters(tmp_path: Path) -> None:
    """``filter -p`` prints rosbag filter's MATCH / NO MATCH lines, messages decoded alike."""
    src = ROS1 / "roswire" / "hello_world_example.bag"
    expression = "'1' in (m.data if topic == '/chatter' else m.msg)"
    show = "topic + ' ' + str(t.to_sec()) + ' ' + str(m.header.seq if topic != '/chatter' else 0)"
    theirs = subprocess.run(
        ["rosbag", "filter", str(src), str(tmp_path / "r.bag"), expression, "-p", show],
        capture_output=True, text=True, timeout=600, check=True,
    )  # fmt: skip
    mine = run_cli("bag", "filter", str(src), str(tmp_path / "o.bag"), expression, "-p", show)
    assert mine.returncode == 0, mine.stderr
    # rosbag's progress meter shares stdout with the lines ("...ETAMATCH /t ...")
    verdicts = re.findall(r"(?:NO )?MATCH [^\r\n]*", theirs.stdout)
    assert mine.stdout.splitlines() == verdicts
    assert len(verdicts) == bag_info(src).message_count
    assert ours(tmp_path / "o.bag") == ours(tmp_path / "r.bag")


@pytest.mark.parametrize(("name", "words"), sorted(NOT_BAGS.items()))
def test_not_bags_give_one_line_errors(name: str, words: str) -> None:
    with pytest.raises(BagFormatError, match=words) as caught:
        open_bag(ROS1 / name)
    assert "\n" not in str(caught.value)


@pytest.mark.parametrize(("name", "parent"), sorted(DERIVED.items()))
def test_cut_bags_read_and_recover_a_prefix(tmp_path: Path, name: str, parent: str) -> None:
    path = CORPUS / "ros1-derived" / name
    full = ours(ROS1 / parent)
    got = ours(path)
    assert got == full[: len(got)]
    assert len(got) > 0.5 * len(full)
    report = recover(path, tmp_path / "out.bag")
    assert ours(tmp_path / "out.bag") == got
    assert report.messages == len(got)
    assert not report.was_indexed
    assert bag_info(tmp_path / "out.bag").indexed
    if name.startswith("test1"):  # cut inside a bz2 chunk: that chunk is reported lost
        assert not report.complete
    else:  # cut exactly at the index: every chunk is whole
        assert report.complete


@needs_ros1
def test_rosbag_reads_our_recovered_bags(tmp_path: Path) -> None:
    dump = Path(__file__).parent.parent / "support" / "rosbag_dump.py"
    outs = []
    for name in sorted(DERIVED):
        out = tmp_path / name
        recover(CORPUS / "ros1-derived" / name, out)
        outs.append(out)
    proc = subprocess.run(
        [SYSTEM_PYTHON, str(dump), *map(str, outs)], capture_output=True, text=True, check=True
    )
    theirs = json.loads(proc.stdout)
    for out in outs:
        assert theirs[str(out)]["stream"] == ours(out)


def conformance_files() -> list[Path]:
    return sorted((CORPUS / "mcap" / "conformance").rglob("*.mcap"))


def to_json(value: Any) -> Any:
    """A record field as the conformance JSON writes it: numbers and bytes as strings."""
    if isinstance(value, bytes):
        return [str(b) for b in value]
    if isinstance(value, dict):
        return {str(k): to_json(v) for k, v in value.items()}
    if isinstance(value, int):
        return str(value)
    return value


def _spec_name(record: object) -> str:
    """The MCAP specification's name for a record (ours for Message is MessageRecord)."""
    name = type(record).__name__
    return "Message" if name == "MessageRecord" else name


@pytest.mark.parametrize("path", conformance_files(), ids=lambda p: p.stem)
def test_mcap_conformance(path: Path) -> None:
    expected = json.loads(path.with_suffix(".json").read_text())["records"]
    streamed = []
    for record in mcap_format.stream(path.read_bytes()):
        if isinstance(record, mcap_format.MessageIndex):
            continue  # the suite's streamed output leaves message indexes out
        fields = record._asdict()
        if isinstance(record, mcap_format.Attachment):
            fields.pop("crc")  # ... and attachment CRCs
        streamed.append(
            {
                "type": _spec_name(record),
                "fields": sorted([k, to_json(v)] for k, v in fields.items()),
            }
        )
    assert streamed == expected
    messages = [dict(r["fields"]) for r in expected if r["type"] == "Message"]
    wanted = sorted(
        (
            (int(m["channel_id"]), int(m["log_time"]), bytes(int(b) for b in m["data"]))
            for m in messages
        ),
        key=lambda m: m[1],
    )
    with McapReader(path) as reader:
        assert [(c.id, t, bytes(d)) for c, t, d in reader.messages()] == wanted
        assert reader.info().message_count == len(messages)
        assert not reader.damage


def rosbag2_folders() -> list[Path]:
    return sorted(p.parent for p in (CORPUS / "mcap" / "rosbag2").rglob("metadata.yaml"))


@pytest.mark.parametrize("folder", rosbag2_folders(), ids=lambda p: p.name)
def test_rosbag2_mcap_counts_match_metadata(folder: Path) -> None:
    meta = yaml.safe_load((folder / "metadata.yaml").read_text())["rosbag2_bagfile_information"]
    counts: dict[str, int] = {}
    total = 0
    for path in sorted(folder.glob("*.mcap")):
        info = bag_info(path)
        assert info.profile == "ros2"
        total += info.message_count
        for topic in info.topics:
            counts[topic.topic] = counts.get(topic.topic, 0) + topic.messages
    assert total == meta["message_count"]
    for entry in meta["topics_with_message_count"]:
        assert counts.get(entry["topic_metadata"]["name"], 0) == entry["message_count"]


def test_every_corpus_mcap_is_described() -> None:
    for path in sorted((CORPUS / "mcap").rglob("*.mcap")):
        info = bag_info(path)
        with open_bag(path) as reader:
            assert sum(1 for _ in reader.messages()) == info.message_count


def test_no_traceback_for_any_corpus_file() -> None:
    for path in sorted(CORPUS.rglob("*")):
        if path.is_file() and path.suffix in (".bag", ".mcap", ".txt"):
            try:
                with open_bag(path) as reader:
                    reader.info()
                    for _ in reader.messages():
                        pass
            except RostoolsError as err:
                assert "\n" not in str(err)


def conformance_extras() -> list[Path]:
    return [p for p in conformance_files() if p.parent.name in ("OneAttachment", "OneMetadata")]


@pytest.mark.parametrize("path", conformance_extras(), ids=lambda p: p.stem)
def test_convert_keeps_mcap_attachments_and_metadata(path: Path, tmp_path: Path) -> None:
    """What the suite says the file holds comes out of our copy, indexed for the mcap library."""
    from mcap.reader import make_reader

    from rostools.bag.tools.ops import convert

    expected = [
        r for r in json.loads(path.with_suffix(".json").read_text())["records"]
        if r["type"] in ("Attachment", "Metadata")
    ]  # fmt: skip
    report = convert(path, tmp_path / "out.mcap")
    assert (report.extras_copied, report.extras_left_out) == (len(expected), 0)
    with McapReader(tmp_path / "out.mcap") as reader:
        extras = reader.extras()
    got = []
    for record in extras:
        fields = record._asdict()
        fields.pop("crc", None)
        got.append(
            {
                "type": _spec_name(record),
                "fields": sorted([k, to_json(v)] for k, v in fields.items()),
            }
        )
    assert got == expected
    with (tmp_path / "out.mcap").open("rb") as f:
        theirs = make_reader(f)
        indexed = [*theirs.iter_attachments(), *theirs.iter_metadata()]
        stats = theirs.get_summary().statistics  # type: ignore[union-attr]
    assert [(type(r).__name__, r.name) for r in indexed] == [
        (type(r).__name__, r.name) for r in extras
    ]
    assert stats is not None and stats.attachment_count + stats.metadata_count == len(expected)
    to_bag = convert(path, tmp_path / "out.bag")
    assert (to_bag.extras_copied, to_bag.extras_left_out) == (0, len(expected))


TALKER = CORPUS / "mcap" / "rosbag2" / "rosbag2_py" / "talker" / "talker.mcap"


@pytest.mark.parametrize(
    ("args", "command"),
    [
        (["topic", "echo", "-b", "{bag}", "/topic", "-n", "1"], "topic echo -b"),
        (["bag", "filter", "{bag}", "{tmp}/out.mcap", "m.data == 'x'"], "a filter expression"),
        (["bag", "play", "{bag}", "-d", "0"], "bag play"),
    ],
    ids=lambda v: v if isinstance(v, str) else None,
)
def test_ros2_cdr_mcap_is_refused_in_one_line_not_misdecoded(
    args: list[str], command: str, tmp_path: Path
) -> None:
    """Issue 13, defect 5: echo used to decode CDR as ROS 1 ("shorter than its type says")."""
    filled = [a.replace("{bag}", str(TALKER)).replace("{tmp}", str(tmp_path)) for a in args]
    done = run_cli(*filled)
    assert done.returncode == 1 and done.stdout == "", done.stdout
    assert done.stderr.count("\n") == 1 and "Traceback" not in done.stderr
    assert "holds ROS 2 CDR messages" in done.stderr
    assert f"{command} does not support ROS 2 CDR" in done.stderr
    assert not list(tmp_path.iterdir())


@needs_corpus
def test_attachments_and_metadata_commands(tmp_path: Path) -> None:
    """``bag attachments`` lists and extracts what the suite says the file holds; ``bag
    metadata`` prints its records; a .bag has neither."""
    folder = CORPUS / "mcap" / "conformance"
    attached = folder / "OneAttachment" / "OneAttachment-ax-pad-st-sum.mcap"
    described = folder / "OneMetadata" / "OneMetadata-mdx-pad-st-sum.mcap"
    listed = run_cli("bag", "attachments", str(attached), "-F", "json")
    assert listed.returncode == 0, listed.stderr
    assert json.loads(listed.stdout) == [
        {"name": "myFile", "media_type": "application/octet-stream", "log_time": 2,
         "create_time": 1, "size": 3}
    ]  # fmt: skip
    text = run_cli("bag", "attachments", str(attached)).stdout.splitlines()
    assert text[0].split()[:2] == ["name", "media"] and text[1].split()[0] == "myFile"
    out = tmp_path / "got.bin"
    got = run_cli("bag", "attachments", str(attached), "--get", "myFile", "-o", str(out))
    assert got.returncode == 0 and out.read_bytes() == b"\x01\x02\x03", got.stderr
    missing = run_cli("bag", "attachments", str(attached), "--get", "nope")
    assert missing.returncode == 3 and "no attachment named 'nope' (it has: myFile)" in (
        missing.stderr
    )
    meta = run_cli("bag", "metadata", str(described))
    assert json.loads(meta.stdout) == [{"name": "myMetadata", "metadata": {"foo": "bar"}}]
    bag = CORPUS / "ros1" / "roswire" / "simple.bag"
    assert json.loads(run_cli("bag", "metadata", str(bag)).stdout) == []
