"""The offline cases: rosmsg/rossrv, rosbag and rostopic -b, run once (no master).

Bag cases read ``graph.bag`` and ``graph_lz4.bag`` (written by real rosbag from the graph)
and the third-party bags of the shared corpus; the commands that change files work on
fresh copies, one folder per side, and what the files hold afterwards is compared with
real rosbag's own reading of them.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from benchmarks.parity import documented as d
from benchmarks.parity.cases import case as online_case, error, rules, usage, verb_usage
from benchmarks.parity.compare import Expect, Pairing
from benchmarks.parity.runner import Case

#: rosbag info of a file another command wrote: its size and ratios depend on the writer's
#: compression, which is not the question; what it holds is.
SIZES = (
    (r"(?m)^(size|uncompressed|compressed): .*$", r"\1: SIZE"),
    (r"compression: +(\w+) \[(\d+)/(\d+) chunks.*\]", r"compression: \1 [\2/\3 chunks]"),
    (r"(?m)^(\w+:) +", r"\1 "),
)


def case(ident: str, ros1: str, ours: str | None = None, **kw: Any) -> Case:
    """An offline case: run once, with no master."""
    return online_case(ident, ros1, ours, online=False, **kw)


def msg_cases() -> list[Case]:
    """rosmsg and rossrv."""
    got: list[Case] = []
    shows = ("std_msgs/String", "geometry_msgs/PointStamped", "sensor_msgs/JointState",
             "nav_msgs/Odometry", "sensor_msgs/PointCloud2", "std_msgs/MultiArrayLayout",
             "visualization_msgs/Marker", "actionlib_msgs/GoalStatus", "rosgraph_msgs/Log",
             "sensor_msgs/Imu", "Header", "Point", "String")  # fmt: skip
    for t in shows:
        got.append(case(f"msg-show-{t.replace('/', '-')}", f"rosmsg show {t}"))
    for t in ("std_msgs/Header", "geometry_msgs/Pose", "visualization_msgs/Marker"):
        got.append(case(f"msg-show-raw-{t.replace('/', '-')}", f"rosmsg show -r {t}"))
    for t in ("std_srvs/SetBool", "roscpp/GetLoggers", "nav_msgs/GetPlan", "Trigger"):
        got.append(case(f"srv-show-{t.replace('/', '-')}", f"rossrv show {t}", f"msg show {t}"))
    for t in (
        "std_msgs/String",
        "Header",
        "geometry_msgs/PoseStamped",
        "visualization_msgs/Marker",
    ):
        got.append(case(f"msg-md5-{t.replace('/', '-')}", f"rosmsg md5 {t}"))
    for t in ("std_srvs/SetBool", "roscpp/GetLoggers"):
        got.append(case(f"srv-md5-{t.replace('/', '-')}", f"rossrv md5 {t}", f"msg md5 {t}"))
    msgs = rules(d.BUILTIN_TYPES, expect=Expect(kind="msg"))
    srvs = rules(d.BUILTIN_TYPES, expect=Expect(kind="srv"))
    got += [
        case(
            "msg-show-raw-srv",
            "rossrv show -r std_srvs/Trigger",
            "msg show -r std_srvs/Trigger",
        ),
        case("msg-info-alias", "rosmsg info std_msgs/String"),
        case("msg-show-suffix", "rosmsg show std_msgs/String.msg"),
        case("msg-show-bag", "rosmsg show -b graph.bag sensor_msgs/JointState"),
        case(
            "msg-show-bag-no-type",
            "rosmsg show -b graph.bag nope/Nope",
            pairing=error(3, d.SHOW_BAG_LACKS_TYPE),
        ),
        case(
            "msg-show-bag-missing",
            "rosmsg show -b nope.bag std_msgs/String",
            pairing=error(3),
        ),
        case("msg-show-unknown", "rosmsg show nope/Nope", pairing=error(3)),
        case("msg-show-unknown-bare", "rosmsg show Nope", pairing=error(3)),
        case("msg-show-cpp", "rosmsg show std_msgs::String", pairing=error(2)),
        case(
            "msg-show-srv-as-msg",
            "rosmsg show std_srvs/SetBool",
            pairing=rules(d.MSG_AND_SRV),
        ),
        case(
            "srv-show-msg-as-srv",
            "rossrv show std_msgs/String",
            "msg show std_msgs/String",
            pairing=rules(d.MSG_AND_SRV),
        ),
        case("msg-md5-unknown", "rosmsg md5 nope/Nope", pairing=error(3)),
        case("msg-list", "rosmsg list", pairing=msgs),
        case("srv-list", "rossrv list", "msg list --srv", pairing=srvs),
        case("msg-package", "rosmsg package std_msgs"),
        case("msg-package-s", "rosmsg package -s geometry_msgs"),
        case("msg-package-no-msgs", "rosmsg package std_srvs"),
        case("srv-package", "rossrv package std_srvs", "msg package --srv std_srvs"),
        case("srv-package-s", "rossrv package -s roscpp", "msg package -s --srv roscpp"),
        case("msg-package-unknown", "rosmsg package nopkg", pairing=error(3)),
        case("msg-packages", "rosmsg packages", pairing=msgs),
        case("msg-packages-s", "rosmsg packages -s", pairing=msgs),
        case("srv-packages", "rossrv packages", "msg packages --srv", pairing=srvs),
        case("srv-packages-s", "rossrv packages -s", "msg packages -s --srv", pairing=srvs),
        case("msg-none", "rosmsg", "msg", pairing=verb_usage()),
        case("msg-bogus", "rosmsg bogus", pairing=verb_usage()),
        case("msg-md5-missing", "rosmsg md5", pairing=usage()),
    ]
    return got


def _folder_out(_graph: object, cwd: Path) -> None:
    """An empty folder ``out`` beside the bag (for --output-dir)."""
    (cwd / "out").mkdir()


def _info_check(*names: str) -> tuple[str, ...]:
    return tuple(f"rosbag info {n}" for n in names)


def bag_cases(corpus: Path) -> list[Case]:
    """rosbag, rostopic -b, on the graph's bags and the corpus."""
    changed = Pairing(normalise=SIZES, rules=(d.PROGRESS,))
    reindexed = Pairing(normalise=SIZES, rules=(d.PROGRESS, d.REINDEX_SAYS))
    got = [
        case("bag-info", "rosbag info graph.bag"),
        case("bag-info-lz4", "rosbag info graph_lz4.bag"),
        case("bag-info-two", "rosbag info graph.bag graph_lz4.bag"),
        case("bag-info-freq", "rosbag info --freq graph.bag"),
        case("bag-info-y", "rosbag info -y graph.bag", pairing=rules(d.INFO_YAML)),
        case("bag-info-y-lz4", "rosbag info -y graph_lz4.bag", pairing=rules(d.INFO_YAML)),
        case("bag-info-k", "rosbag info -y -k duration graph.bag"),
        case("bag-info-k-topics", "rosbag info -y -k topics graph.bag"),
        case("bag-info-k-version", "rosbag info -y -k version graph.bag"),
        case("bag-info-k-compression", "rosbag info -y -k compression graph_lz4.bag"),
        case(
            "bag-info-k-alone",
            "rosbag info -k messages graph.bag",
            pairing=rules(d.K_IMPLIES_Y),
        ),
        case("bag-info-missing", "rosbag info nope.bag", pairing=error(3)),
        case("bag-info-not-bag", "rosbag info text.txt", pairing=error(1)),
        case("bag-info-none", "rosbag info", pairing=usage()),
        case("topic-list-bag", "rostopic list -b graph.bag"),
        case("topic-list-bag-topic", "rostopic list -b graph.bag /point"),
        case("topic-echo-bag", "rostopic echo -b graph.bag /chatter"),
        case("topic-echo-bag-n", "rostopic echo -b graph.bag -n 2 /point"),
        case("topic-echo-bag-csv", "rostopic echo -b graph.bag -p /joints"),
        case("topic-echo-bag-noarr", "rostopic echo -b graph.bag --noarr -n 1 /joints"),
        case("topic-echo-bag-field", "rostopic echo -b graph.bag /point/point/x"),
        case("topic-echo-bag-latched", "rostopic echo -b graph_lz4.bag /latched"),
        case(
            "topic-echo-bag-filter",
            "rostopic echo -b graph.bag --filter \"m.data.endswith('5')\" /chatter",
        ),
        case("topic-echo-bag-missing", "rostopic echo -b nope.bag /chatter", pairing=error(3)),
        case(
            "bag-filter",
            "rosbag filter graph.bag out.bag \"topic == '/chatter'\"",
            files=("graph.bag",),
            checks=_info_check("out.bag"),
            listing=True,
            pairing=changed,
        ),
        case(
            "bag-filter-m",
            "rosbag filter graph.bag out.bag \"topic == '/chatter' and m.data.endswith('1')\"",
            files=("graph.bag",),
            checks=(*_info_check("out.bag"), "rostopic echo -b out.bag /chatter"),
            pairing=changed,
        ),
        case(
            "bag-filter-t",
            "rosbag filter graph_lz4.bag out.bag "
            "\"t.to_sec() > 0 and topic in ('/point', '/joints')\"",
            files=("graph_lz4.bag",),
            checks=_info_check("out.bag"),
            pairing=changed,
        ),
        case(
            "bag-filter-bad-expr",
            'rosbag filter graph.bag out.bag "topic =="',
            files=("graph.bag",),
            listing=True,
            pairing=error(2),
        ),
        case("bag-filter-missing", 'rosbag filter nope.bag out.bag "True"', pairing=error(3)),
        case(
            "bag-compress",
            "rosbag compress graph.bag",
            files=("graph.bag",),
            listing=True,
            checks=_info_check("graph.bag", "graph.orig.bag"),
            pairing=changed,
        ),
        case(
            "bag-compress-lz4",
            "rosbag compress --lz4 graph.bag",
            files=("graph.bag",),
            listing=True,
            checks=_info_check("graph.bag"),
            pairing=changed,
        ),
        case(
            "bag-decompress",
            "rosbag decompress graph_lz4.bag",
            files=("graph_lz4.bag",),
            listing=True,
            checks=_info_check("graph_lz4.bag", "graph_lz4.orig.bag"),
            pairing=changed,
        ),
        case(
            "bag-compress-backup-exists",
            "rosbag compress graph.bag",
            files=("graph.bag", "graph.orig.bag"),
            listing=True,
            checks=_info_check("graph.bag"),
            pairing=changed,
        ),
        case(
            "bag-compress-force",
            "rosbag compress -f graph.bag",
            files=("graph.bag", "graph.orig.bag"),
            listing=True,
            checks=_info_check("graph.bag"),
            pairing=changed,
        ),
        case(
            "bag-decompress-plain",
            "rosbag decompress graph.bag",
            files=("graph.bag",),
            listing=True,
            checks=_info_check("graph.bag"),
            pairing=changed,
        ),
        case("bag-compress-missing", "rosbag compress nope.bag", pairing=error(3)),
        case(
            "bag-reindex",
            "rosbag reindex graph.bag",
            files=("graph.bag",),
            listing=True,
            checks=_info_check("graph.bag"),
            pairing=reindexed,
        ),
        case(
            "bag-reindex-outdir",
            "rosbag reindex --output-dir out graph.bag",
            files=("graph.bag",),
            setup=_folder_out,
            listing=True,
            checks=_info_check("graph.bag", "out/graph.bag"),
            pairing=reindexed,
        ),
        case(
            "bag-reindex-outdir-missing",
            "rosbag reindex --output-dir out graph.bag",
            files=("graph.bag",),
            listing=True,
            pairing=error(2),
        ),
        case("bag-reindex-missing", "rosbag reindex nope.bag", pairing=error(3)),
        case("bag-none", "rosbag", "bag", pairing=verb_usage()),
        case("bag-bogus", "rosbag bogus", pairing=verb_usage()),
    ]
    cut = "example_cut_at_index_pos.bag"
    if (corpus / "ros1-derived" / cut).exists():
        salvage = Pairing(normalise=SIZES, rules=(d.PROGRESS, d.MORE_SALVAGED, d.REINDEX_SAYS))
        got.append(case("bag-reindex-cut", f"rosbag reindex {cut}", listing=True, limit=60.0,
                        files=(f"{{corpus}}/ros1-derived/{cut}",), checks=_info_check(cut),
                        pairing=salvage))  # fmt: skip
    got += corpus_cases(corpus)
    return got


#: Corpus files that are not bags a reader should open, and the small ones echo reads.
NOT_BAGS = ("empty-file.bag", "asci-file.txt", "invalid.bag", "dummy.bag")
#: Its chunks are out of time order: echoed whole (rosbag's -n would take another 2 first).
UNSORTED = "example-unsorted-chunks.bag"
ECHO_BAGS = 8


def corpus_cases(corpus: Path) -> list[Case]:
    """rosbag info of every ROS 1 corpus bag; topic list/echo and msg show of small ones."""
    got: list[Case] = []
    bags = sorted((corpus / "ros1").rglob("*.bag")) + sorted((corpus / "ros1").rglob("*.txt"))
    bags += sorted((corpus / "ros1-derived").glob("*.bag"))
    small: list[Path] = []
    for path in bags:
        rel = path.relative_to(corpus)
        ident = "corpus-" + str(rel.with_suffix("")).replace("/", "-")
        if path.name in NOT_BAGS:
            got.append(case(f"{ident}-info", f"rosbag info {{corpus}}/{rel}", pairing=error(1)))
            continue
        info = rules(d.UNSORTED_CHUNKS, d.UNINDEXED_INFO)
        got.append(case(f"{ident}-info", f"rosbag info {{corpus}}/{rel}", limit=60.0, pairing=info))
        if "derived" not in str(rel) and path.stat().st_size < 400_000:
            small.append(path)
    for path in small[:: max(1, len(small) // ECHO_BAGS)][:ECHO_BAGS]:
        rel = path.relative_to(corpus)
        ident = "corpus-" + str(rel.with_suffix("")).replace("/", "-")
        topic, msgtype = _first_topic(path)
        got.append(case(f"{ident}-list", f"rostopic list -b {{corpus}}/{rel}"))
        if topic is None:
            continue
        some = "" if path.name == UNSORTED else "-n 2 "
        echo = rules(d.TIME_ORDER)
        got.append(case(f"{ident}-echo", f"rostopic echo -b {{corpus}}/{rel} {some}{topic}",
                        pairing=echo))  # fmt: skip
        got.append(
            case(
                f"{ident}-echo-csv",
                f"rostopic echo -b {{corpus}}/{rel} {some}-p {topic}",
                pairing=rules(d.CSV_BYTES, d.TIME_ORDER),
            )
        )
        got.append(case(f"{ident}-show", f"rosmsg show -b {{corpus}}/{rel} {msgtype}"))
    return got


def _first_topic(path: Path) -> tuple[str | None, str]:
    """The first topic of a bag (by name) and its type, read by rosbags (a third party)."""
    from rosbags.rosbag1 import Reader

    try:
        with Reader(path) as reader:
            conns = sorted(reader.connections, key=lambda c: c.topic)
            with_messages = [c for c in conns if c.msgcount > 0] or conns
            if not with_messages:
                return None, ""
            # rosbags names types as ROS 2 does (pkg/msg/Name)
            return with_messages[0].topic, with_messages[0].msgtype.replace("/msg/", "/")
    except Exception:  # noqa: BLE001 - a bag rosbags cannot read gets no echo case
        return None, ""


def offline_cases(corpus: Path) -> list[Case]:
    """Every case that needs no master."""
    return [*msg_cases(), *bag_cases(corpus)]
