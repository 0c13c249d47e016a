"""The known differences between the ROS 1 tools and rostools, each where the docs say so.

A case names the differences that may apply to it; ``compare.judge`` takes each out in
turn, and a pair that then agrees is "documented". Every ``readme`` phrase must be in
README.md or a page of docs/ (whitespace collapsed): ``check_docs`` says which are not, and
the harness refuses to run while one is missing. A difference found that no entry here covers is a
defect, not a documented one.
"""

from __future__ import annotations

import re
from pathlib import Path

import yaml

from benchmarks.parity.compare import Difference, Expect, Output

# rostopic's status lines, printed on stdout, which rostools prints on stderr.
STATUS = re.compile(
    r"^(subscribed to \[.*\]|publishing and latching .*|publishing message .*|"
    r"Got one message and a rate.*)$"
)


def _status_to_stderr(a: Output, b: Output, _: Expect) -> tuple[Output, Output]:
    lines = a.stdout.splitlines(keepends=True)
    moved = [line for line in lines if STATUS.match(line.rstrip("\n"))]
    if not moved:
        return a, b
    kept = "".join(line for line in lines if line not in moved)
    return a.but(stdout=kept, stderr="".join(moved) + a.stderr), b


def _anon_names(a: Output, b: Output, _: Expect) -> tuple[Output, Output]:
    def rename(text: str) -> str:
        return re.sub(r"/rostools_[a-z_]+?_ANON", "/rostopic_ANON", text)

    return a, b.but(stdout=rename(b.stdout), stderr=rename(b.stderr), effects=rename(b.effects))


def _sort_blocks(text: str) -> str:
    """Each run of ``" * "`` lines sorted."""
    out: list[str] = []
    run: list[str] = []
    for line in [*text.split("\n"), None]:
        if line is not None and line.startswith(" * "):
            run.append(line)
            continue
        out.extend(sorted(run))
        run = []
        if line is not None:
            out.append(line)
    return "\n".join(out)


def _list_v_sorted(a: Output, b: Output, _: Expect) -> tuple[Output, Output]:
    return a.but(stdout=_sort_blocks(a.stdout)), b


def _sorted_lines(a: Output, b: Output, _: Expect) -> tuple[Output, Output]:
    lines = a.stdout.splitlines()
    return a.but(stdout="".join(f"{line}\n" for line in sorted(lines))), b


def _ros1_signalled_error(a: Output) -> bool:
    words = ("error", "unknown", "cannot", "not ", "invalid", "unable", "usage", "no such")
    return a.code != 0 or any(w in a.stderr.lower() for w in words)


def _one_line_error(a: Output, b: Output, e: Expect) -> tuple[Output, Output]:
    if e.error is None or not _ros1_signalled_error(a):
        return a, b
    lines = b.stderr.splitlines()
    if b.stdout or len(lines) != 1 or not lines[0].startswith("rostools: "):
        return a, b
    return a.but(stdout=b.stdout, stderr=b.stderr), b


def _exit_code(a: Output, b: Output, e: Expect) -> tuple[Output, Output]:
    if e.error is None or b.code != e.error or not _ros1_signalled_error(a):
        return a, b
    return a.but(code=b.code), b


UNLOADABLE = re.compile(r"Unable to load type|Cannot load message class|Unable to load msg")


def _types_from_peer(a: Output, b: Output, _: Expect) -> tuple[Output, Output]:
    # rosservice printed what it could before it failed; rostools prints that and the rest
    if (
        a.code != 0
        and UNLOADABLE.search(a.stderr)
        and b.code == 0
        and b.stdout.startswith(a.stdout)
    ):
        return b, b
    return a, b


def _pretty_mapping(a: Output, b: Output, e: Expect) -> tuple[Output, Output]:
    """rosparam get -p of a mapping: ours must read back as the value, rosparam's must not.

    Where both print ``key: scalar`` for one key, the scalars may differ only where
    rosparam's reads back as another value (``''`` printed bare, ``'123'`` unquoted).
    """
    try:
        ours = yaml.safe_load(b.stdout)
    except yaml.YAMLError:
        return a, b
    try:
        theirs = yaml.safe_load(a.stdout)
    except yaml.YAMLError:
        theirs = None
    if ours != e.value or theirs == e.value:
        return a, b
    pairs = re.compile(r"^(\s*)([^\s:]+): (\S.*)$")
    scalars_a = {(m[1], m[2]): m[3] for m in map(pairs.match, a.stdout.splitlines()) if m}
    for line in b.stdout.splitlines():
        m = pairs.match(line)
        if m is None or (m[1], m[2]) not in scalars_a:
            continue
        theirs_text = scalars_a[(m[1], m[2])]
        if theirs_text == m[3]:
            continue
        try:
            same_value = yaml.safe_load(theirs_text) == yaml.safe_load(m[3])
        except yaml.YAMLError:
            same_value = False
        if same_value:
            return a, b  # an undocumented difference: rosparam's text was valid too
    return b, b


def _file_in(effects: str, name: str) -> str | None:
    """The text of file ``name`` as the case's effects show it; None when it was not there."""
    marker = f"== file {name}\n"
    if marker not in effects:
        return None
    text = effects.split(marker, 1)[1].split("\n== ", 1)[0]
    return None if text == "(none)\n" else text


def _dump_dash(a: Output, b: Output, _: Expect) -> tuple[Output, Output]:
    # rosparam dump - writes a file named "-"; the case's effects show it
    written = _file_in(a.effects, "-")
    if a.stdout or written is None or _file_in(b.effects, "-") is not None:
        return a, b
    if written.rstrip("\n") != b.stdout.rstrip("\n"):
        return a, b
    return b, b


BUILTIN_SERVICE_PACKAGES = (
    "std_srvs",
    "roscpp",
    "nav_msgs",
    "sensor_msgs",
    "diagnostic_msgs",
    "dynamic_reconfigure",
    "rospy_tutorials",
    "roscpp_tutorials",
)


def _builtin_types(a: Output, b: Output, e: Expect) -> tuple[Output, Output]:
    """rostools lists the types of its built-in table too, installed or not."""
    theirs, ours = a.stdout.split(), b.stdout.split()
    extra = [w for w in ours if w not in theirs]
    if not extra or [w for w in ours if w in theirs] != theirs:
        return a, b
    if e.kind == "srv" and any(w.split("/")[0] not in BUILTIN_SERVICE_PACKAGES for w in extra):
        return a, b
    return b.but(code=a.code, stderr=a.stderr), b


def _contains(big: object, small: object) -> bool:
    if isinstance(small, dict) and isinstance(big, dict):
        return all(k in big and _contains(big[k], v) for k, v in small.items())
    if isinstance(small, list) and isinstance(big, list):
        return len(big) == len(small) and all(map(_contains, big, small))
    return big == small


def _info_yaml_data(a: Output, b: Output, _: Expect) -> tuple[Output, Output]:
    try:
        theirs, ours = yaml.safe_load(a.stdout), yaml.safe_load(b.stdout)
    except yaml.YAMLError:
        return a, b
    if isinstance(theirs, dict) and _contains(ours, theirs):
        return a.but(stdout=b.stdout), b
    return a, b


def _waits_notice(a: Output, b: Output, _: Expect) -> tuple[Output, Output]:
    """A wait with no end: each tool says on stderr what it waits for, in its own words."""
    if a.stopped and b.stopped and a.stdout == b.stdout and a.stderr and b.stderr:
        return a.but(stderr=b.stderr), b
    return a, b


def _timeout_exit(a: Output, b: Output, _: Expect) -> tuple[Output, Output]:
    """ROS 1 had to be stopped; rostools' --timeout ended it with exit 5."""
    if a.stopped and not b.stopped and b.code == 5 and a.stdout == b.stdout:
        return a.but(code=5, stderr=b.stderr, stopped=False), b
    return a, b


def _rel(text: str) -> str:
    return re.sub(r"\s+", " ", text).strip()


D = Difference
STATUS_STDERR = D(
    "status-stderr",
    "rostopic prints status lines on stdout, rostools on stderr",
    "Status lines (`subscribed to [/t]`, `publishing and latching message`) go to stderr, "
    "where rostopic prints them on stdout",
    _status_to_stderr,
)
ANON_NAMES = D(
    "anon-names",
    "rostools' short-lived nodes are named after the command, rostopic's /rostopic_PID_MS",
    "The short-lived node a command runs as is named after the command, "
    "`/rostools_echo_<pid>_<ms>`",
    _anon_names,
)
LIST_V_SORTED = D(
    "list-v-sorted",
    "topic list -v sorts each block; rostopic keeps the master's order",
    "`-v` sorts, where rostopic keeps the master's order",
    _list_v_sorted,
)
FIND_SORTED = D(
    "find-sorted",
    "topic find sorts; rostopic keeps the master's order",
    "`rostools topic find TYPE` (sorted)",
    _sorted_lines,
)
ONE_LINE_ERROR = D(
    "one-line-error",
    "an error is one line on stderr, 'rostools: ...', in rostools' words",
    "Errors print one line on stderr (`rostools: <what went wrong> (hint: ...)`)",
    _one_line_error,
)
#: The docs' row for each exit code an error case may give.
EXIT_ROWS = {
    1: "| 1 | error | the operation failed, or the input data is malformed (`bag info`: the bag "
    "is unindexed) |",
    2: "| 2 | usage | bad arguments or values: unknown option, wrong field type, bad YAML |",
    3: "| 3 | not found | unknown topic, type, service, parameter, node or file |",
    4: "| 4 | unreachable | the master or a peer node could not be contacted |",
    5: "| 5 | timeout | a wait ran past its --timeout |",
}
EXIT_CODES = {
    code: D(f"exit-{code}", f"rostools exits {code} for this class of error", row, _exit_code)
    for code, row in EXIT_ROWS.items()
}
TYPES_FROM_PEER = D(
    "types-from-peer",
    "rostools learns a service's type from the server; rosservice needs it installed",
    "`type` and `info` learn a service's type from the server itself (a `probe` header), so "
    "they work for custom services installed nowhere on this machine",
    _types_from_peer,
)
PRETTY_MAPPING = D(
    "get-p-yaml",
    "param get -p of a mapping stays valid YAML; rosparam's breaks lists and quoting",
    "`get -p` of a mapping stays valid YAML, where rosparam's breaks its lists",
    _pretty_mapping,
)
DUMP_DASH = D(
    "dump-dash",
    "param dump - prints to stdout; rosparam dump - writes a file named '-'",
    "`rostools param dump [FILE] [ns]` (no FILE or `-`: stdout)",
    _dump_dash,
)
BUILTIN_TYPES = D(
    "builtin-types",
    "msg list/packages include the built-in table's types, installed or not",
    "the built-in table: rosbags' Noetic store (162 message types) and the common Noetic "
    "services (std_srvs, roscpp, nav_msgs, sensor_msgs, diagnostic_msgs, "
    "dynamic_reconfigure, rospy_tutorials/AddTwoInts, roscpp_tutorials/TwoInts)",
    _builtin_types,
)
INFO_YAML = D(
    "info-y-data",
    "bag info -y prints rostools' data (a superset of rosbag's keys)",
    "`--format json|yaml` (or `-y`) gives data",
    _info_yaml_data,
)
WAITS_NOTICE = D(
    "waits-notice",
    "a wait without a limit is announced on stderr in rostools' words",
    "A wait without a limit says once, on stderr, what it is waiting for.",
    _waits_notice,
)
TIMEOUT_EXIT = D(
    "timeout-exit",
    "rostools --timeout ends a wait with exit 5 where the ROS 1 tool runs until stopped",
    "Every command that waits takes `--timeout`; on a topic nobody publishes, `echo`, "
    "`hz`, `bw` and `delay` say so once and exit 5 at the timeout.",
    _timeout_exit,
)


def _progress(a: Output, b: Output, _: Expect) -> tuple[Output, Output]:
    """rosbag prints a progress bar on stdout, even into a pipe; rostools a summary."""
    bar = "\r" in a.stdout or "ETA" in a.stdout
    summary = b.stderr.startswith("wrote ") and len(b.stderr.splitlines()) == 1
    if not bar and not summary:
        return a, b
    return a.but(stdout="" if bar else a.stdout), b.but(stderr="" if summary else b.stderr)


def _says_what_it_recovered(a: Output, b: Output, _: Expect) -> tuple[Output, Output]:
    """reindex says, as recover does, how many messages it got back (and why it scanned)."""
    lines = b.stderr.splitlines()
    said = [x for x in lines if x.startswith(("recovered ", "note: "))]
    if not said or a.stderr or len(said) != len(lines):
        return a, b
    return a, b.but(stderr="")


def _csv_keeps_bytes(a: Output, b: Output, _: Expect) -> tuple[Output, Output]:
    """rostools' CSV keeps the columns of a uint8[] field (NAME0, NAME1, ...); rostopic drops
    them. Those columns, and only those, are taken out of rostools' rows."""
    ours, theirs = b.stdout.splitlines(), a.stdout.splitlines()
    if not ours or not theirs or len(ours) != len(theirs) or not ours[0].startswith("%time"):
        return a, b
    head_b, head_a = ours[0].split(","), theirs[0].split(",")
    extra = [i for i, col in enumerate(head_b) if col not in head_a]
    names = {re.sub(r"\d+$", "", head_b[i]) for i in extra}
    if not extra or len(names) != 1 or not all(re.search(r"\d$", head_b[i]) for i in extra):
        return a, b
    keep = [i for i in range(len(head_b)) if i not in extra]
    rows = []
    for line in ours:
        cells = line.split(",")
        if len(cells) != len(head_b):
            return a, b
        rows.append(",".join(cells[i] for i in keep))
    return a, b.but(stdout="".join(f"{r}\n" for r in rows))


PROGRESS = D(
    "progress",
    "rosbag's progress bar goes to stdout into a pipe too; rostools shows one on a terminal "
    "and prints a one-line summary on stderr",
    "Both show a progress bar on a terminal, NDJSON progress with `--format json`",
    _progress,
)


def _accepted(a: Output, b: Output, _: Expect) -> tuple[Output, Output]:
    if a.code not in (0, None) and b.code == 0:
        return b, b
    return a, b


K_IMPLIES_Y = D(
    "k-implies-y",
    "bag info -k without -y prints the value; rosbag refuses",
    "the same flags (`-k` alone implies `-y`)",
    _accepted,
)
MSG_AND_SRV = D(
    "msg-and-srv",
    "rostools msg shows message and service types alike; rossrv and rosmsg each know one",
    "Message and service types both work everywhere",
    _accepted,
)


def _more_salvaged(a: Output, b: Output, _: Expect) -> tuple[Output, Output]:
    """rostools' reindex keeps messages of a cut last chunk that rosbag reindex drops."""
    count = re.compile(r"^messages: +(\d+)$", re.M)
    ca, cb = count.findall(a.effects), count.findall(b.effects)
    if not ca or len(ca) != len(cb) or any(int(x) > int(y) for x, y in zip(ca, cb, strict=True)):
        return a, b
    masked = re.compile(r"(?m)^(duration|end|messages|topics| +/)\b.*$")
    if masked.sub("", a.effects) != masked.sub("", b.effects):
        return a, b
    return a.but(effects=b.effects), b


MORE_SALVAGED = D(
    "reindex-salvages-more",
    "reindex keeps the complete messages of a cut last chunk, which rosbag reindex drops",
    "including those inside a partially written last chunk, which `rosbag reindex` throws away",
    _more_salvaged,
)

REINDEX_SAYS = D(
    "reindex-says",
    "bag reindex says on stderr how many messages it recovered, as bag recover does",
    "says what it lost and exits 6 if it lost anything. **reindex** does the same to several "
    "bags in place",
    _says_what_it_recovered,
)
CSV_BYTES = D(
    "csv-bytes",
    "echo -p keeps uint8[]/char[] columns, which rostopic drops",
    "CSV keeps `uint8[]`/`char[]` columns, which rostopic drops",
    _csv_keeps_bytes,
)

SERVICE_FIND_SORTED = D(
    "service-find-sorted",
    "service find sorts; rosservice keeps the master's order",
    "`rostools service find TYPE` (sorted)",
    _sorted_lines,
)


def _ping_blocks(text: str) -> str:
    """``rosnode ping -a``'s output with its list and its pings each in name order."""
    head, sep, pings = _sort_blocks(text).partition("\n\n")
    blocks = re.split(r"(?m)^(?=pinging )", pings)
    return head + sep + "".join(blocks[:1] + sorted(blocks[1:]))


def _ping_all_sorted(a: Output, b: Output, _: Expect) -> tuple[Output, Output]:
    return a.but(stdout=_ping_blocks(a.stdout)), b


PING_ALL_SORTED = D(
    "ping-all-sorted",
    "node ping -a lists and pings the nodes in sorted order; rosnode in the master's",
    "(`-a` pings in sorted order)",
    _ping_all_sorted,
)

#: rosnode cleanup's question, which rostools asks on stderr.
CLEANUP_QUESTION = re.compile(
    r"(?m)^(Warning: these might include .*|Cleanup will purge .*|"
    r"Please type y or n to continue: ?)(\n|$)"
)


def _cleanup_reasons(a: Output, b: Output, _: Expect) -> tuple[Output, Output]:
    """Ours names why each node is unreachable and asks on stderr; rosnode prints a
    connection error on stderr and asks on stdout."""
    if not CLEANUP_QUESTION.search(a.stdout) or not CLEANUP_QUESTION.search(b.stderr):
        return a, b
    errors = re.sub(r"(?m)^ERROR: connection refused to \[.*\]\n", "", a.stderr)
    theirs = a.but(stdout=CLEANUP_QUESTION.sub("", a.stdout), stderr=errors)
    reasons = re.sub(r"(?m)^( \* \S+) \(.*\)$", r"\1", b.stdout)
    return theirs, b.but(stdout=reasons, stderr=CLEANUP_QUESTION.sub("", b.stderr))


CLEANUP_OUTPUT = D(
    "cleanup-output",
    "node cleanup gives each unreachable node's reason and asks on stderr",
    "(each unreachable node with the reason; the question on stderr)",
    _cleanup_reasons,
)


def _verb_usage(a: Output, b: Output, _: Expect) -> tuple[Output, Output]:
    """No verb or an unknown one: ROS 1 prints its verbs and exits 0 (or 64); ours exit 2."""
    if b.code == 2 and a.code in (0, 64) and (a.stdout or a.stderr):
        return a.but(code=2), b
    return a, b


VERB_USAGE = D(
    "verb-usage",
    "a missing or unknown verb is a usage error, exit 2; rosparam, rosmsg and rosbag exit 0",
    "A group named without a verb, or with one it lacks (`rostools param`, `rostools param "
    "bogus`), is a usage error, exit 2, with the list of verbs (rosparam, rosmsg and rosbag "
    "print it and exit 0; rostopic, rosservice and rosnode exit 64).",
    _verb_usage,
)


def _silent_ros1_then_one_line(a: Output, b: Output, e: Expect) -> tuple[Output, Output]:
    """ROS 1 printed nothing and exited 0; ours is a one-line error with the expected code."""
    quiet = a.code == 0 and not a.stdout.strip() and not a.stderr.strip()
    lines = b.stderr.splitlines()
    one_line = not b.stdout and len(lines) == 1 and lines[0].startswith("rostools: ")
    if quiet and one_line and e.error is not None and b.code == e.error:
        return b, b
    return a, b


SHOW_BAG_LACKS_TYPE = D(
    "show-bag-lacks-type",
    "msg show -b of a type the bag lacks is exit 3; rosmsg prints nothing and exits 0",
    "a type the bag lacks is exit 3, where rosmsg prints nothing and exits 0",
    _silent_ros1_then_one_line,
)

PUBLISHING_LINE = re.compile(r"(?m)^publishing and latching message for [\d.]+ seconds\n")


def _pub_file_quiet(a: Output, b: Output, _: Expect) -> tuple[Output, Output]:
    if PUBLISHING_LINE.search(b.stdout + b.stderr):
        return a, b
    return a.but(
        stdout=PUBLISHING_LINE.sub("", a.stdout), stderr=PUBLISHING_LINE.sub("", a.stderr)
    ), b


PUB_FILE_QUIET = D(
    "pub-file-quiet",
    "pub from a file or stdin says nothing per message; rostopic prints a line for each",
    '`pub` from a file or stdin says nothing per message, where rostopic prints "publishing '
    'and latching message for 3.0 seconds" for each',
    _pub_file_quiet,
)

INFO_TIMES = re.compile(r"(?m)^(duration|start|end):.*\n")


def _unsorted_chunks(a: Output, b: Output, _: Expect) -> tuple[Output, Output]:
    """rosbag info of a bag whose chunks are out of time order: a negative duration."""
    if not re.search(r"(?m)^duration:\s+-", a.stdout) or a.code != b.code:
        return a, b
    if INFO_TIMES.sub("", a.stdout) != INFO_TIMES.sub("", b.stdout):
        return a, b
    return a.but(stdout=b.stdout), b


UNSORTED_CHUNKS = D(
    "unsorted-chunks-info",
    "bag info of a bag whose chunks are out of time order gives its true start and end; "
    "rosbag takes them from the first and last chunk and prints a negative duration",
    "rosbag takes the start from the first chunk in the file and the end from the last, and "
    "prints a negative duration (`-1.0s`); ours gives the bag's first and last times",
    _unsorted_chunks,
)


def _messages(text: str) -> tuple[str, list[str]]:
    """An echo's output as (CSV header or "", the messages): YAML documents or CSV rows."""
    if text.startswith("%time"):
        head, _, rows = text.partition("\n")
        return head, rows.splitlines()
    return "", text.split("---\n")


def _time_order(a: Output, b: Output, _: Expect) -> tuple[Output, Output]:
    """The same messages, ours in time order, rosbag's in the order of the file's chunks."""
    head_a, theirs = _messages(a.stdout)
    head_b, ours = _messages(b.stdout)
    if head_a != head_b or theirs == ours or sorted(theirs) != sorted(ours):
        return a, b
    if head_b:
        stamps = [int(row.split(",", 1)[0]) for row in ours]
        if stamps != sorted(stamps):
            return a, b
    return a.but(stdout=b.stdout), b


TIME_ORDER = D(
    "time-order",
    "a bag whose chunks are out of time order is read in time order; rosbag yields it in "
    "the order of its chunks",
    "A bag whose chunks are out of time order is read in time order by every command",
    _time_order,
)


def _unindexed_info(a: Output, b: Output, _: Expect) -> tuple[Output, Output]:
    """rosbag info refuses an unindexed bag, exit 1; ours summarises it and says so, exit 1
    (6 when data was lost too)."""
    refused = a.code == 1 and not a.stdout and "ERROR bag unindexed" in a.stderr
    said = b.code in (1, 6) and "unindexed: " in b.stderr and b.stdout.startswith("path:")
    return (b, b) if refused and said else (a, b)


UNINDEXED_INFO = D(
    "unindexed-info",
    "bag info of an unindexed bag prints the summary and says so in one line, exit 1 as "
    "rosbag (6 if data was lost)",
    "`info` prints the summary and makes that line its error, exit 1 as rosbag info",
    _unindexed_info,
)

ALL = (
    STATUS_STDERR,
    ANON_NAMES,
    LIST_V_SORTED,
    FIND_SORTED,
    ONE_LINE_ERROR,
    *EXIT_CODES.values(),
    TYPES_FROM_PEER,
    PRETTY_MAPPING,
    DUMP_DASH,
    BUILTIN_TYPES,
    INFO_YAML,
    WAITS_NOTICE,
    TIMEOUT_EXIT,
    PROGRESS,
    K_IMPLIES_Y,
    MSG_AND_SRV,
    MORE_SALVAGED,
    REINDEX_SAYS,
    CSV_BYTES,
    SERVICE_FIND_SORTED,
    PING_ALL_SORTED,
    CLEANUP_OUTPUT,
    VERB_USAGE,
    SHOW_BAG_LACKS_TYPE,
    PUB_FILE_QUIET,
    UNSORTED_CHUNKS,
    UNINDEXED_INFO,
    TIME_ORDER,
)


def error(code: int) -> tuple[Difference, ...]:
    """What an error case may need: rostools' own words, the exit code of its class."""
    return (ONE_LINE_ERROR, EXIT_CODES[code])


def check_docs(root: Path) -> list[str]:
    """The keys of the differences whose phrase neither README.md nor a page of docs/ contains."""
    pages = [root / "README.md", *sorted((root / "docs").glob("*.md"))]
    text = _rel(" ".join(page.read_text() for page in pages))
    return [d.key for d in ALL if _rel(d.readme) not in text]
