"""What two runs printed, made comparable, and the verdict on a pair: pure, no processes.

A paired run is one case run with the ROS 1 tool and with its rostools twin on one master.
Both outputs are normalised for what legitimately varies (anonymous node names, PIDs, ports
of short-lived connections, times, stamps, rates within a tolerance), then compared. What
still differs is a known, documented difference (``documented.py``), a failure of the ROS 1
tool, or a defect.
"""

from __future__ import annotations

import difflib
import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from enum import Enum


class Verdict(str, Enum):
    """The class of a paired run, or of a case (its worst run)."""

    IDENTICAL = "identical"
    DOCUMENTED = "documented"
    ROS1_FAILURE = "ros1-failure"
    DEFECT = "defect"


#: From the best verdict to the worst: a case is as bad as its worst run.
SEVERITY = (Verdict.IDENTICAL, Verdict.DOCUMENTED, Verdict.ROS1_FAILURE, Verdict.DEFECT)

TRACEBACK = "Traceback (most recent call last)"


@dataclass(frozen=True)
class Output:
    """What one command did: its exit code (None: it hung and was killed) and its text.

    ``stopped`` says the harness ended it with SIGINT as the case planned (hz, echo
    without -n); ``effects`` is what the case's checks printed afterwards (a parameter read
    back, the files a bag command left), compared like stdout.
    """

    code: int | None
    stdout: str
    stderr: str
    stopped: bool = False
    effects: str = ""

    def but(self, **changes: object) -> Output:
        """A copy with some fields changed."""
        return replace(self, **changes)  # type: ignore[arg-type]

    @property
    def crashed(self) -> bool:
        """It hung past its limit or printed a Python traceback."""
        return self.code is None or TRACEBACK in self.stderr or self.code < 0


@dataclass(frozen=True)
class Expect:
    """What a case knows about the right answer, for the rules that need it.

    ``error``: the exit code the docs give rostools for this error case (None: not an
    error case). ``value``: the parameter value a ``get -p`` prints. ``kind``: "msg" or
    "srv" for listings of types.
    """

    error: int | None = None
    value: object = None
    kind: str = "msg"


#: A documented difference: given both outputs (normalised) and the case's expectations,
#: the outputs with that difference taken out (unchanged when it does not apply).
Transform = Callable[[Output, Output, Expect], tuple[Output, Output]]


@dataclass(frozen=True)
class Difference:
    """A known difference between a ROS 1 tool and rostools, and where the docs say so."""

    key: str
    reason: str
    #: A phrase of README.md or docs/ (whitespace collapsed) that documents the difference.
    readme: str
    apply: Transform


@dataclass(frozen=True)
class Pairing:
    """How a case compares its two outputs.

    ``streams``: "all" (exit code, stdout, stderr, effects), "stdout" (stderr ignored: a
    tool's own diagnostics) or "code" (exit codes only: help and usage texts).
    ``normalise``: extra (pattern, replacement) pairs for this case's varying text.
    ``rates``: the first number after each of these words at the start of a line
    (``average``, a topic in hz's table) is a measurement, compared within ``tolerance``;
    every other number is masked and repeated lines are counted once.
    """

    streams: str = "all"
    normalise: tuple[tuple[str, str], ...] = ()
    rates: tuple[str, ...] = ()
    tolerance: float = 0.25
    rules: tuple[Difference, ...] = ()
    expect: Expect = field(default_factory=Expect)


# What varies between any two runs, whichever tool prints it.
GENERIC: tuple[tuple[str, str], ...] = (
    (r"/rostopic_\d+_\d+", "/rostopic_ANON"),
    (r"/rosservice_\d+_\d+", "/rosservice_ANON"),
    (r"/rosnode_\d+_\d+", "/rosnode_ANON"),
    (r"/record_\d+_\d+", "/record_ANON"),
    (r"/rostools_([a-z_]+?)_\d+_\d+", r"/rostools_\1_ANON"),
    (r"Pid: \d+", "Pid: PID"),
    # a node's connections: local port, peer address, connection id
    (r"\(\d+ - [0-9.]+:\d+\) \[\d+\]", "(PORT - PEER) [ID]"),
    (r"time=[0-9.]+ms", "time=MS"),
    (r"ping average: [0-9.]+ms", "ping average: MS"),
    (r"\[ *(INFO|WARN|ERROR|DEBUG)\] \[\d+\.\d+\]", r"[\1] [TIME]"),
)

# What varies between two live subscriptions to one topic: which message came first.
LIVE: tuple[tuple[str, str], ...] = (
    # CSV rows: %time (ns), then header.seq and header.stamp where the message has them
    (r"(?m)^\d{18,20},", "T,"),
    (r"(?m)^T,\d+,\d{18,20},", "T,N,T,"),
    (r"\bseq: \d+", "seq: N"),
    (r"\bsecs: \d{9,}", "secs: T"),
    (r"hello \d+", "hello N"),
)


def _nsecs(text: str) -> str:
    """nsecs values masked, their printed width kept (rostopic pads to nine digits)."""
    return re.sub(r"\bnsecs:( *\d+)", lambda m: f"nsecs:<{len(m.group(1))} wide>", text)


def normalise_text(text: str, extra: Sequence[tuple[str, str]] = (), live: bool = False) -> str:
    """``text`` with the generic patterns, ``extra`` and (``live``) the live ones masked."""
    patterns = [*GENERIC, *(LIVE if live else ()), *extra]
    for pattern, repl in patterns:
        text = re.sub(pattern, repl, text)
    return _nsecs(text) if live else text


def normalise(out: Output, extra: Sequence[tuple[str, str]] = (), live: bool = False) -> Output:
    """Every stream of ``out`` normalised."""
    return out.but(
        stdout=normalise_text(out.stdout, extra, live),
        stderr=normalise_text(out.stderr, extra, live),
        effects=normalise_text(out.effects, extra, live),
    )


NUMBER = re.compile(r"-?\d+(?:\.\d+)?(?:e[-+]?\d+)?")


def measurements(text: str, word: str) -> list[float]:
    """The leading number of each line that starts with ``word``."""
    found = []
    for line in text.splitlines():
        if line.strip().startswith(word):
            match = NUMBER.search(line[line.index(word) + len(word) :])
            if match:
                found.append(float(match.group()))
    return found


def shape(text: str) -> str:
    """``text`` with numbers masked, spaces and rules collapsed, each distinct line once."""
    seen: dict[str, None] = {}
    for line in text.splitlines():
        line = re.sub(r"=+", "=", re.sub(r"\s+", " ", NUMBER.sub("#", line))).strip()
        seen.setdefault(line, None)
    return "\n".join(seen)


def rates_agree(a: str, b: str, words: Sequence[str], tolerance: float) -> str | None:
    """Why the measurements of ``a`` and ``b`` disagree, or None when they agree."""
    for word in words:
        ma, mb = measurements(a, word), measurements(b, word)
        if not ma or not mb:
            if ma or mb:
                return f"{word}: {ma} against {mb}"
            continue
        # the median, as the first window or the one cut short by SIGINT is often off
        xa, xb = sorted(ma)[len(ma) // 2], sorted(mb)[len(mb) // 2]
        scale = max(abs(xa), abs(xb))
        # delays near zero: a few milliseconds either way are the same answer
        if scale >= 0.01 and abs(xa - xb) > tolerance * scale:
            return f"median {word} {xa:g} against {xb:g}, more than {tolerance:.0%} apart"
    return None


def streams_of(out: Output, which: str) -> dict[str, object]:
    """The parts of ``out`` a pairing compares."""
    if which == "code":
        return {"exit": out.code}
    parts: dict[str, object] = {"exit": out.code, "stdout": out.stdout, "effects": out.effects}
    if which == "all":
        parts["stderr"] = out.stderr
    return parts


def same(a: Output, b: Output, pairing: Pairing) -> bool:
    """Whether ``a`` and ``b`` agree on what ``pairing`` compares."""
    if pairing.rates:
        a = a.but(stdout=shape(a.stdout), stderr=shape(a.stderr))
        b = b.but(stdout=shape(b.stdout), stderr=shape(b.stderr))
    return streams_of(a, pairing.streams) == streams_of(b, pairing.streams)


def diff(a: Output, b: Output, pairing: Pairing, limit: int = 40) -> str:
    """A short unified diff of what still differs (ROS 1 first)."""
    lines: list[str] = []
    sa, sb = streams_of(a, pairing.streams), streams_of(b, pairing.streams)
    for key in sa:
        if sa[key] == sb[key]:
            continue
        if key == "exit":
            lines.append(f"exit: {sa[key]} (ROS 1) != {sb[key]} (rostools)")
            continue
        lines.extend(
            difflib.unified_diff(
                str(sa[key]).splitlines(),
                str(sb[key]).splitlines(),
                f"ros1 {key}",
                f"rostools {key}",
                n=1,
                lineterm="",
            )
        )
    if len(lines) > limit:
        lines = [*lines[:limit], f"... {len(lines) - limit} more lines"]
    return "\n".join(lines)


@dataclass(frozen=True)
class Judgement:
    """The verdict on one paired run, the documented differences it needed, and a diff."""

    verdict: Verdict
    rules: tuple[str, ...] = ()
    detail: str = ""


def ros1_failed_alone(ros1: Output, ours: Output) -> bool:
    """The ROS 1 tool hung or crashed where rostools answered (no traceback, no hang).

    A traceback counts even when the harness stopped the tool as planned: rostopic hz
    prints one when Ctrl-C ends its wait for a topic.
    """
    failed = (ros1.code is None and not ros1.stopped) or TRACEBACK in ros1.stderr
    return failed and not ours.crashed


def judge(ros1: Output, ours: Output, pairing: Pairing, live: bool = False) -> Judgement:
    """The verdict on one paired run (outputs as the tools printed them)."""
    a = normalise(ros1, pairing.normalise, live)
    b = normalise(ours, pairing.normalise, live)
    off = (
        rates_agree(a.stdout, b.stdout, pairing.rates, pairing.tolerance) if pairing.rates else None
    )
    if off is None and same(a, b, pairing):
        return Judgement(Verdict.IDENTICAL)
    if ros1_failed_alone(ros1, ours):
        why = "hung" if ros1.code is None else "crashed"
        return Judgement(
            Verdict.ROS1_FAILURE, detail=f"the ROS 1 tool {why}\n" + diff(a, b, pairing)
        )
    used: list[str] = []
    for rule in pairing.rules:
        a2, b2 = rule.apply(a, b, pairing.expect)
        if (a2, b2) != (a, b):
            used.append(rule.key)
            a, b = a2, b2
    if off is None and same(a, b, pairing):
        return Judgement(Verdict.DOCUMENTED, tuple(used))
    detail = diff(a, b, pairing)
    if off is not None:
        detail = f"{off}\n{detail}".strip()
    return Judgement(Verdict.DEFECT, tuple(used), detail)


def worst(verdicts: Sequence[Verdict]) -> Verdict:
    """The worst of several verdicts (a case's class from its runs)."""
    return max(verdicts, key=SEVERITY.index) if verdicts else Verdict.IDENTICAL
