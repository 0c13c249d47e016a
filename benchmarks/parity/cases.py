"""The online cases: rostopic, rosservice, rosparam and rosnode on the graph.

Each case is a ROS 1 command line and its rostools twin; most twins are the same words
after ``rostools GROUP``. A case lists the documented differences that may apply to it.
"""

from __future__ import annotations

import signal
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from benchmarks.parity import documented as d
from benchmarks.parity.compare import Difference, Expect, Pairing
from benchmarks.parity.graph import PARAMS, Graph
from benchmarks.parity.runner import Case, Setup
from tests.support.procs import start_ros1_node, wait_for

GROUPS = {
    "rostopic": "topic",
    "rosservice": "service",
    "rosparam": "param",
    "rosnode": "node",
    "rosmsg": "msg",
    "rossrv": "msg",
    "rosbag": "bag",
}


def twin(ros1: str) -> str:
    """The rostools arguments with the same words as a ROS 1 command line."""
    tool, _, rest = ros1.partition(" ")
    return f"{GROUPS[tool]} {rest}".strip()


def case(ident: str, ros1: str, ours: str | None = None, **kw: Any) -> Case:
    """A case; ``ours`` defaults to the same words under the rostools group."""
    tool = ros1.split()[0]
    return Case(ident, tool, ros1, ours if ours is not None else twin(ros1), **kw)


def rules(*diffs: Difference, **kw: Any) -> Pairing:
    """A pairing that allows these documented differences."""
    return Pairing(rules=diffs, **kw)


def error(code: int, *more: Difference, streams: str = "all") -> Pairing:
    """An error case: rostools exits ``code`` with one line, in its own words."""
    return Pairing(streams=streams, rules=(*more, *d.error(code)), expect=Expect(error=code))


def usage(streams: str = "code") -> Pairing:
    """Bad arguments: help and usage texts differ by nature; the exit codes are compared."""
    return error(2, streams=streams)


def verb_usage() -> Pairing:
    """A group without a verb, or with one it lacks: ROS 1 prints its verbs (exit 0 or 64)."""
    return error(2, d.VERB_USAGE, streams="code")


def reset(graph: Graph | None, _cwd: Path) -> Callable[[], None]:
    """Parameters as the graph started, before each side of a case that changes them and
    after it, so that no later case sees what this one changed."""
    assert graph is not None
    graph.reset_params()
    return graph.reset_params


def victim(kill: bool) -> Setup:
    """A rospy talker named /victim (SIGKILLed, still registered, when ``kill``)."""

    def setup(graph: Graph | None, _cwd: Path) -> Callable[[], None]:
        assert graph is not None
        proc = start_ros1_node(
            "talker.py", ["/victim_chatter", "2", "0", "-1", "__name:=victim"], graph.env
        )

        def registered() -> bool:
            # its topic, not lookupNode: roscore still knows a purged node's name
            publishers = graph.call("getSystemState")[0]
            return any(t == "/victim_chatter" and "/victim" in n for t, n in publishers)

        wait_for(registered, 30, "/victim to register")
        time.sleep(0.5)
        if kill:
            proc.signal(signal.SIGKILL)
            proc.popen.wait()
        return lambda: (proc.stop(), None)[1]

    return setup


def topic_cases() -> list[Case]:
    """rostopic."""
    echo = rules(d.STATUS_STDERR)
    rate = rules(d.STATUS_STDERR, rates=("average",))
    table = rules(d.STATUS_STDERR, rates=("/point", "/joints"))
    pub = rules(d.STATUS_STDERR, d.ANON_NAMES)
    pub_file = rules(d.PUB_FILE_QUIET, d.STATUS_STDERR, d.ANON_NAMES)
    return [
        case("topic-list", "rostopic list"),
        case("topic-list-ns", "rostopic list /chatter"),
        case("topic-list-v", "rostopic list -v", pairing=rules(d.LIST_V_SORTED)),
        case("topic-list-p", "rostopic list -p"),
        case("topic-list-s", "rostopic list -s"),
        case("topic-list-v-p", "rostopic list -v -p", pairing=rules(d.LIST_V_SORTED)),
        case("topic-list-host", "rostopic list --host"),
        case("topic-list-v-ns", "rostopic list -v /point", pairing=rules(d.LIST_V_SORTED)),
        case("topic-info-latched", "rostopic info /latched"),
        case("topic-type-relative", "rostopic type chatter"),
        case("topic-echo-relative", "rostopic echo -n 1 latched", pairing=rules(d.STATUS_STDERR)),
        case("topic-list-p-s", "rostopic list -p -s", pairing=error(2)),
        case("topic-info", "rostopic info /chatter"),
        case("topic-info-point", "rostopic info /point"),
        case("topic-info-rosout", "rostopic info /rosout"),
        case("topic-info-unknown", "rostopic info /nope", pairing=error(3)),
        case("topic-info-missing", "rostopic info", pairing=usage()),
        case("topic-type", "rostopic type /chatter"),
        case("topic-type-field", "rostopic type /point/point/x"),
        case("topic-type-submsg", "rostopic type /point/header"),
        case("topic-type-array", "rostopic type /joints/name"),
        case("topic-type-unknown", "rostopic type /nope", pairing=error(3)),
        case("topic-find", "rostopic find std_msgs/String", pairing=rules(d.FIND_SORTED)),
        case("topic-find-one", "rostopic find geometry_msgs/PointStamped"),
        case("topic-find-none", "rostopic find nope/Nope"),
        case("topic-echo-point", "rostopic echo -n 1 /point", pairing=echo, live=True),
        case("topic-echo-chatter-2", "rostopic echo -n 2 /chatter", pairing=echo, live=True),
        case("topic-echo-latched", "rostopic echo -n 1 /latched", pairing=echo),
        case("topic-echo-field-msg", "rostopic echo -n 1 /point/point", pairing=echo),
        case("topic-echo-field-float", "rostopic echo -n 1 /point/point/x", pairing=echo),
        case("topic-echo-field-array", "rostopic echo -n 1 /joints/name", pairing=echo),
        case("topic-echo-index", "rostopic echo -n 1 /joints/position[1]", pairing=echo),
        case("topic-echo-slice", "rostopic echo -n 1 /joints/name[1:]", pairing=echo),
        case("topic-echo-noarr", "rostopic echo -n 1 --noarr /joints", pairing=echo, live=True),
        case("topic-echo-nostr", "rostopic echo -n 1 --nostr /joints", pairing=echo, live=True),
        case("topic-echo-nostr-str", "rostopic echo -n 1 --nostr /latched", pairing=echo),
        case("topic-echo-csv", "rostopic echo -n 2 -p /point", pairing=echo, live=True),
        case("topic-echo-csv-str", "rostopic echo -n 1 -p /chatter", pairing=echo, live=True),
        case(
            "topic-echo-csv-noarr", "rostopic echo -n 1 -p --noarr /joints", pairing=echo, live=True
        ),
        case(
            "topic-echo-csv-nostr", "rostopic echo -n 1 -p --nostr /joints", pairing=echo, live=True
        ),
        case(
            "topic-echo-csv-latched",
            "rostopic echo -n 1 -p /latched",
            pairing=rules(d.STATUS_STDERR, normalise=((r"(?m)^\d{18,20},", "T,"),)),
        ),
        case("topic-echo-width", "rostopic echo -n 1 -w 5 /point/point", pairing=echo),
        case(
            "topic-echo-filter",
            "rostopic echo -n 1 --filter \"m.data.startswith('hello')\" /chatter",
            pairing=echo,
            live=True,
        ),
        case(
            "topic-echo-filter-topic",
            "rostopic echo -n 1 --filter \"topic == '/chatter'\" /chatter",
            pairing=echo,
            limit=8.0,
            live=True,
        ),
        case(
            "topic-echo-offset",
            "rostopic echo -n 1 --offset /point/header",
            pairing=echo,
            live=True,
        ),
        case("topic-echo-clear", "rostopic echo -n 1 -c /latched", pairing=echo),
        case(
            "topic-echo-bad-field", "rostopic echo -n 1 /chatter/dat", pairing=error(2), limit=8.0
        ),
        case(
            "topic-echo-unpublished",
            "rostopic echo /nope",
            pairing=rules(d.WAITS_NOTICE),
            stop_after=3.0,
        ),
        case(
            "topic-echo-timeout",
            "rostopic echo /nope",
            "topic echo /nope --timeout 2",
            pairing=rules(d.TIMEOUT_EXIT, d.WAITS_NOTICE),
            stop_after=3.5,
        ),
        case("topic-echo-missing", "rostopic echo", pairing=error(2)),
        case("topic-echo-bad-count", "rostopic echo -n x /chatter", pairing=usage()),
        case("topic-hz", "rostopic hz /point", pairing=rate, stop_after=4.0),
        case("topic-hz-two", "rostopic hz /point /joints", pairing=table, stop_after=4.0),
        case("topic-hz-window", "rostopic hz -w 5 /point", pairing=rate, stop_after=4.0),
        case(
            "topic-hz-filter",
            'rostopic hz --filter "m.point.x > 0" /point',
            pairing=rate,
            stop_after=4.0,
        ),
        case("topic-hz-wall", "rostopic hz --wall-time /chatter", pairing=rate, stop_after=4.0),
        case(
            "topic-hz-unpublished",
            "rostopic hz /nope",
            pairing=rules(d.WAITS_NOTICE),
            stop_after=3.0,
        ),
        case("topic-bw", "rostopic bw /point", pairing=rate, stop_after=4.0),
        case("topic-bw-window", "rostopic bw -w 5 /chatter", pairing=rate, stop_after=4.0),
        case("topic-delay", "rostopic delay /point", pairing=rate, stop_after=4.0),
        case("topic-delay-window", "rostopic delay -w 5 /joints", pairing=rate, stop_after=4.0),
        case("topic-delay-no-header", "rostopic delay /chatter", pairing=rate, stop_after=4.0),
        case("topic-hz-missing", "rostopic hz", pairing=error(2)),
        case(
            "topic-pub-once",
            "rostopic pub -1 /pub_once std_msgs/String 'data: hi'",
            pairing=pub,
            observe="rostopic echo -n 1 /pub_once",
        ),
        case(
            "topic-pub-positional",
            "rostopic pub -1 /pub_positional geometry_msgs/Point 1 2 3",
            pairing=pub,
            observe="rostopic echo -n 1 /pub_positional",
        ),
        case(
            "topic-pub-header-auto",
            "rostopic pub -1 /pub_header_auto geometry_msgs/PointStamped "
            "'{header: auto, point: {x: 1.5}}'",
            pairing=pub,
            observe="rostopic echo -n 1 /pub_header_auto",
            live=True,
        ),
        case(
            "topic-pub-negative",
            "rostopic pub -1 /pub_negative std_msgs/Int32 -- -5",
            pairing=pub,
            observe="rostopic echo -n 1 /pub_negative",
        ),
        case(
            "topic-pub-verbose",
            "rostopic pub -1 -v /pub_verbose std_msgs/String 'data: v'",
            pairing=pub,
            observe="rostopic echo -n 1 /pub_verbose",
        ),
        case(
            "topic-pub-stdin",
            "rostopic pub /pub_stdin std_msgs/String",
            # rostopic drops a last document that no --- ends (so does rosservice)
            stdin="data: one\n---\ndata: two\n---\n",
            pairing=pub_file,
            observe="rostopic echo -n 2 /pub_stdin",
        ),
        case(
            "topic-pub-file",
            "rostopic pub /pub_file std_msgs/String -f msgs.yaml",
            files=("msgs.yaml",),
            pairing=pub_file,
            observe="rostopic echo -n 2 /pub_file",
        ),
        case(
            "topic-pub-rate",
            "rostopic pub -r 5 /pub_rate std_msgs/String 'data: r'",
            pairing=pub,
            stop_after=4.0,
            observe="rostopic echo -n 3 /pub_rate",
        ),
        case(
            "topic-pub-bad-field",
            "rostopic pub -1 /pub_bad_field std_msgs/String '{bad: 1}'",
            pairing=error(2),
        ),
        case(
            "topic-pub-too-many",
            "rostopic pub -1 /pub_too_many std_msgs/Int32 1 2",
            pairing=error(2),
        ),
        case(
            "topic-pub-bad-type",
            "rostopic pub -1 /pub_bad_type nope/Nope 'data: 1'",
            pairing=error(3),
        ),
        case(
            "topic-pub-bad-yaml",
            "rostopic pub -1 /pub_bad_yaml std_msgs/String '{data: [}'",
            pairing=error(2),
        ),
        case("topic-none", "rostopic", "topic", pairing=verb_usage()),
        case("topic-bogus", "rostopic bogus", pairing=verb_usage()),
        case("topic-bad-option", "rostopic list --bogus", pairing=usage()),
    ]


def service_cases() -> list[Case]:
    """rosservice."""
    peer = rules(d.TYPES_FROM_PEER)
    return [
        case("service-list", "rosservice list"),
        case("service-list-n", "rosservice list -n"),
        case("service-list-ns", "rosservice list /talker"),
        case("service-list-none", "rosservice list /nope"),
        case("service-info", "rosservice info /slow"),
        case("service-info-setbool", "rosservice info /set_bool"),
        case("service-info-custom", "rosservice info /add_two_ints", pairing=peer),
        case("service-info-unknown", "rosservice info /nope", pairing=error(3)),
        case("service-type", "rosservice type /slow"),
        case("service-type-custom", "rosservice type /add_two_ints"),
        case("service-type-unknown", "rosservice type /nope", pairing=error(3)),
        case("service-uri", "rosservice uri /slow"),
        case("service-uri-unknown", "rosservice uri /nope", pairing=error(3)),
        case("service-node", "rosservice node /slow"),
        case("service-node-unknown", "rosservice node /nope", pairing=error(3)),
        case("service-args", "rosservice args /set_bool"),
        case("service-args-empty", "rosservice args /empty"),
        case("service-args-loggers", "rosservice args /talker/set_logger_level"),
        case("service-args-custom", "rosservice args /add_two_ints", pairing=peer),
        case("service-args-unknown", "rosservice args /nope", pairing=error(3)),
        case(
            "service-find",
            "rosservice find std_srvs/Trigger",
            pairing=rules(d.SERVICE_FIND_SORTED),
        ),
        case("service-find-one", "rosservice find std_srvs/SetBool"),
        case("service-find-none", "rosservice find nope/Nope"),
        case("service-call-trigger", "rosservice call /slow"),
        case("service-call-verbose", "rosservice call -v /slow"),
        case("service-call-positional", "rosservice call /set_bool true"),
        case("service-call-mapping", "rosservice call /set_bool 'data: true'"),
        case("service-call-empty", "rosservice call /empty"),
        case("service-call-loggers", "rosservice call /talker/get_loggers"),
        case(
            "service-call-set-logger",
            "rosservice call /talker/set_logger_level '{logger: rosout, level: info}'",
        ),
        case("service-call-custom", "rosservice call /add_two_ints 1 2", pairing=peer),
        case("service-call-wait", "rosservice call --wait /slow"),
        case("service-call-stdin", "rosservice call /set_bool", stdin="data: true\n---\n"),
        case("service-type-relative", "rosservice type slow"),
        case("service-call-refused", "rosservice call /set_bool false", pairing=error(1)),
        case("service-call-too-many", "rosservice call /set_bool true false", pairing=error(2)),
        case("service-call-bad-yaml", "rosservice call /set_bool '{data: [}'", pairing=error(2)),
        case("service-call-bad-field", "rosservice call /set_bool '{nope: 1}'", pairing=error(2)),
        case("service-call-unknown", "rosservice call /nope", pairing=error(3)),
        case("service-call-missing", "rosservice call", pairing=usage()),
        case("service-none", "rosservice", "service", pairing=verb_usage()),
        case("service-bogus", "rosservice bogus", pairing=verb_usage()),
    ]


def _param_set(ident: str, name: str, value: str, check: str = "/scratch", **kw: Any) -> Case:
    quoted = value.replace("'", "'\"'\"'")
    return case(ident, f"rosparam set {name} '{quoted}'", setup=reset,
                checks=(f"rosparam get {check}",), **kw)  # fmt: skip


def _ident(name: str) -> str:
    """A parameter name as part of a case id: /p/int is -p-int, / is -root."""
    return name.replace("/", "-") if name != "/" else "-root"


def param_cases() -> list[Case]:
    """rosparam."""
    got: list[Case] = []
    for name in ("/p", "/p/int", "/p/neg", "/p/float", "/p/small", "/p/bool_t", "/p/text",
                 "/p/multiline", "/p/empty", "/p/unicode", "/p/numeric_str", "/p/list",
                 "/p/mixed", "/p/nested", "/p/empty_map", "/top", "/"):  # fmt: skip
        got.append(case(f"param-get{_ident(name)}", f"rosparam get {name}"))
    mappings = {"/p": PARAMS, "/p/nested": PARAMS["nested"], "/p/empty_map": {}}
    for name, value in mappings.items():
        got.append(case(f"param-get-pretty{_ident(name)}", f"rosparam get -p {name}",
                        pairing=rules(d.PRETTY_MAPPING, expect=Expect(value=value))))  # fmt: skip
    for name in ("/p/multiline", "/p/text", "/p/list", "/p/int", "/p/bool_f", "/p/unicode"):
        got.append(case(f"param-get-pretty{_ident(name)}", f"rosparam get -p {name}"))
    sets = [
        ("int", "/scratch/i", "5"),
        ("float", "/scratch/f", "1.5"),
        ("neg", "/scratch/n", "-3"),
        ("string-num", "/scratch/s", "'123'"),
        ("bool", "/scratch/b", "true"),
        ("list", "/scratch/l", "[1, 2, three]"),
        ("map", "/scratch/m", "{a: 1, b: {c: [1, 2]}}"),
        ("deg", "/scratch/deg", "deg(180)"),
        ("empty-str", "/scratch/e", '""'),
        ("newline", "/scratch/nl", '"a\\nb"'),
        ("exp", "/scratch/x", "1e3"),
        ("unicode", "/scratch/u", "h\u00e9llo"),
    ]
    for ident, name, value in sets:
        got.append(_param_set(f"param-set-{ident}", name, value))
    got += [
        _param_set("param-set-update", "/p/nested", "{s: y, t: 2}", check="/p/nested"),
        _param_set("param-set-verbose", "-v /scratch/v", "{x: 1, y: [1, 2]}"),
        case(
            "param-set-big-int",
            "rosparam set /scratch/big 3000000000",
            setup=reset,
            pairing=error(2),
            checks=("rosparam get /scratch",),
        ),
        case(
            "param-set-date",
            "rosparam set /scratch/date 2024-01-01",
            setup=reset,
            pairing=error(2),
            checks=("rosparam get /scratch",),
        ),
        case(
            "param-set-textfile",
            "rosparam set -t text.txt /scratch/t",
            files=("text.txt",),
            setup=reset,
            checks=("rosparam get /scratch/t",),
        ),
        case("param-set-missing", "rosparam set /scratch/x", pairing=usage()),
        case("param-delete", "rosparam delete /p/int", setup=reset, checks=("rosparam list /p",)),
        case(
            "param-delete-ns",
            "rosparam delete -v /p/nested",
            setup=reset,
            checks=("rosparam list /p",),
        ),
        case("param-delete-unknown", "rosparam delete /nope", pairing=error(3)),
        case("param-list", "rosparam list"),
        case("param-list-ns", "rosparam list /p/nested"),
        case("param-list-none", "rosparam list /nope"),
        case("param-get-unknown", "rosparam get /nope", pairing=error(3)),
        case("param-get-verbose", "rosparam get -v /p/int"),
        case("param-get-relative", "rosparam get p/int"),
        case("param-list-relative", "rosparam list p/nested"),
        case(
            "param-set-binfile",
            "rosparam set -b text.txt /scratch/bin",
            "param set --binfile text.txt /scratch/bin",
            files=("text.txt",),
            setup=reset,
            checks=("rosparam get /scratch/bin",),
        ),
        case("param-get-missing", "rosparam get", pairing=usage()),
        case("param-dump", "rosparam dump"),
        case("param-dump-file", "rosparam dump out.yaml /p", show=("out.yaml",)),
        case("param-dump-verbose", "rosparam dump -v out.yaml /p/nested", show=("out.yaml",)),
        case("param-dump-dash", "rosparam dump - /p", show=("-",), pairing=rules(d.DUMP_DASH)),
        case("param-dump-unknown", "rosparam dump out.yaml /nope", show=("out.yaml",)),
        case(
            "param-load",
            "rosparam load params.yaml /scratch",
            files=("params.yaml",),
            setup=reset,
            checks=("rosparam get /scratch",),
        ),
        case(
            "param-load-verbose",
            "rosparam load -v params.yaml /scratch",
            files=("params.yaml",),
            setup=reset,
            checks=("rosparam get /scratch",),
        ),
        case(
            "param-load-multi",
            "rosparam load multi.yaml",
            files=("multi.yaml",),
            setup=reset,
            checks=("rosparam get /scratch",),
        ),
        case(
            "param-load-stdin",
            "rosparam load - /scratch",
            stdin="a: 1\nb: [x, y]\n",
            setup=reset,
            checks=("rosparam get /scratch",),
        ),
        case("param-load-unknown", "rosparam load nofile.yaml", pairing=error(3)),
        case(
            "param-load-bad",
            "rosparam load bad.yaml /scratch",
            files=("bad.yaml",),
            setup=reset,
            pairing=error(2),
            checks=("rosparam get /scratch",),
        ),
        case("param-none", "rosparam", "param", pairing=verb_usage()),
        case("param-bogus", "rosparam bogus", pairing=verb_usage()),
    ]
    return got


def node_cases() -> list[Case]:
    """rosnode."""
    return [
        case("node-list", "rosnode list"),
        case("node-list-a", "rosnode list -a"),
        case("node-list-u", "rosnode list -u"),
        case("node-list-ns", "rosnode list /talker"),
        case("node-list-none", "rosnode list /nope"),
        case("node-info", "rosnode info /talker"),
        case("node-info-q", "rosnode info -q /talker"),
        case("node-info-peer", "rosnode info -q /graph_peer"),
        case("node-info-server", "rosnode info /add_two_ints_server"),
        case("node-info-two", "rosnode info -q /talker /rosout"),
        case("node-info-unknown", "rosnode info /nope", pairing=error(3)),
        case("node-ping", "rosnode ping -c 2 /talker"),
        case("node-ping-rosout", "rosnode ping -c 1 /rosout"),
        case("node-ping-all", "rosnode ping -a", pairing=rules(d.PING_ALL_SORTED)),
        case("node-info-relative", "rosnode info -q talker"),
        case("node-ping-unknown", "rosnode ping -c 1 /nope", pairing=error(3)),
        case("node-ping-missing", "rosnode ping", pairing=usage()),
        case("node-machine", "rosnode machine"),
        case("node-machine-host", "rosnode machine 127.0.0.1"),
        case("node-machine-none", "rosnode machine 127.0.0.2"),
        case(
            "node-kill",
            "rosnode kill /victim",
            setup=victim(False),
            checks=("rosnode list",),
            pairing=rules(d.ANON_NAMES),
        ),
        case("node-kill-unknown", "rosnode kill /nope", pairing=error(3)),
        case(
            "node-cleanup",
            "rosnode cleanup",
            stdin="y\n",
            setup=victim(True),
            checks=("rosnode list",),
            limit=30.0,
            pairing=rules(d.CLEANUP_OUTPUT),
        ),
        case("node-none", "rosnode", "node", pairing=verb_usage()),
        case("node-bogus", "rosnode bogus", pairing=verb_usage()),
    ]


def online_cases() -> Sequence[Case]:
    """Every case that needs the graph."""
    return [*topic_cases(), *service_cases(), *param_cases(), *node_cases()]
