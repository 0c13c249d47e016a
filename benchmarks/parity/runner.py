"""Running one side of a case: its folder, its setup, the command with bounds, its checks.

Every process runs in its own session and is stopped by its process group (its PID);
a command that outlives its case's limit is stopped and recorded as hung.
"""

from __future__ import annotations

import contextlib
import os
import shlex
import shutil
import signal
import subprocess
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from benchmarks.parity.compare import Output, Pairing
from benchmarks.parity.graph import Graph

#: A case's setup, run before each side on that side's graph and folder; it may return
#: what to do afterwards (stop a process it started).
Setup = Callable[[Graph | None, Path], Callable[[], None] | None]


@dataclass(frozen=True)
class Case:
    """One ROS 1 command line and its rostools twin, and how to run and compare them.

    ``ros1`` and ``ours`` are shell-like command lines (``ours`` without the leading
    ``rostools``); ``{corpus}`` stands for the corpus folder. ``online`` cases run on both
    masters; the rest (bags and types) run once. ``stop_after``: both run that long, then
    get SIGINT (commands that run until stopped). ``files`` are copied into a fresh folder
    for each side, which is then the working folder; ``checks`` (ROS 1 command lines, the
    same for both sides) run after the command and their output is compared as its
    effects, as are the ``show`` files' texts and, with ``listing``, the folder's names.
    ``observe`` is a ROS 1 command started first and stopped after (a subscriber).
    """

    id: str
    tool: str
    ros1: str
    ours: str
    online: bool = True
    pairing: Pairing = field(default_factory=Pairing)
    live: bool = False
    stop_after: float | None = None
    limit: float = 20.0
    stdin: str | None = None
    files: tuple[str, ...] = ()
    checks: tuple[str, ...] = ()
    show: tuple[str, ...] = ()
    listing: bool = False
    observe: str | None = None
    setup: Setup | None = None


@dataclass(frozen=True)
class Place:
    """Where a side runs: its graph (None offline), environment, data and scratch folders."""

    graph: Graph | None
    env: dict[str, str]
    data: Path
    scratch: Path
    corpus: Path
    rostools: tuple[str, ...]


def argv_of(command: str, place: Place) -> list[str]:
    """A command line with ``{corpus}`` and ``{data}`` filled in, split as a shell would."""
    # not str.format: YAML arguments are full of braces
    filled = command.replace("{corpus}", str(place.corpus)).replace("{data}", str(place.data))
    return shlex.split(filled)


def run(
    argv: list[str],
    env: dict[str, str],
    cwd: Path,
    stdin: str | None = None,
    stop_after: float | None = None,
    limit: float = 20.0,
) -> Output:
    """Run ``argv`` once; SIGINT after ``stop_after``, or recorded as hung past ``limit``.

    The command gets SIGINT's default action even where this process ignores it (a shell's
    background job does): its stop is a user's Ctrl-C, which the command must be able to take.
    """
    proc = subprocess.Popen(
        argv,
        env=env,
        cwd=cwd,
        stdin=subprocess.PIPE if stdin is not None else subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        start_new_session=True,
        preexec_fn=_default_sigint if signal.getsignal(signal.SIGINT) == signal.SIG_IGN else None,
    )
    wait = stop_after if stop_after is not None else limit
    stopped = hung = False
    try:
        out, err = proc.communicate(stdin.encode() if stdin is not None else None, timeout=wait)
    except subprocess.TimeoutExpired:
        stopped, hung = stop_after is not None, stop_after is None
        out, err = _stop(proc)
    code = proc.returncode
    if hung or code is None or code == -signal.SIGKILL:
        code = None  # it had to be killed: it hung
    return Output(code, out.decode(errors="replace"), err.decode(errors="replace"), stopped)


def _default_sigint() -> None:
    """In the child, before it runs: SIGINT ends it, whatever its parent did with SIGINT."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _stop(proc: subprocess.Popen[bytes]) -> tuple[bytes, bytes]:
    """SIGINT to its group, then SIGKILL; what it wrote."""
    for sig, grace in ((signal.SIGINT, 6.0), (signal.SIGKILL, 5.0)):
        with contextlib.suppress(ProcessLookupError):
            os.killpg(proc.pid, sig)
        try:
            return proc.communicate(timeout=grace)
        except subprocess.TimeoutExpired:
            continue
    return b"", b""


def _folder(case: Case, place: Place, side: str) -> Path:
    """The working folder of one side: the shared data, or a fresh copy of ``files``."""
    if not case.files and not case.listing and not case.show:
        return place.data
    folder = place.scratch / side / case.id
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir(parents=True)
    for name in case.files:
        source = Path(name.replace("{corpus}", str(place.corpus)))
        shutil.copy2(source if source.is_absolute() else place.data / name, folder / source.name)
    return folder


def _effects(case: Case, place: Place, cwd: Path, observed: str) -> str:
    """What the case's checks, files and listing show after the command."""
    parts: list[str] = []
    if case.observe is not None:
        parts.append(f"== observed\n{observed}")
    for check in case.checks:
        done = run(argv_of(check, place), place.env, cwd, limit=30.0)
        parts.append(f"== {check}\n{done.stdout}{done.stderr}exit {done.code}\n")
    for name in case.show:
        path = cwd / name
        parts.append(f"== file {name}\n{path.read_text() if path.exists() else '(none)'}\n")
    if case.listing:
        names = sorted(p.name for p in cwd.iterdir())
        parts.append("== files\n" + "".join(f"{n}\n" for n in names))
    return "".join(parts)


def run_side(case: Case, place: Place, side: str) -> Output:
    """One side of ``case`` ("ros1" or "ours") at ``place``."""
    cwd = _folder(case, place, side)
    argv = argv_of(case.ros1, place) if side == "ros1" else [
        *place.rostools, *argv_of(case.ours, place)
    ]  # fmt: skip
    teardown = case.setup(place.graph, cwd) if case.setup is not None else None
    observer = None
    try:
        if case.observe is not None:
            observer = subprocess.Popen(
                argv_of(case.observe, place), env=place.env, cwd=cwd,
                stdin=subprocess.DEVNULL, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                start_new_session=True,
            )  # fmt: skip
            time.sleep(2.0)  # a rospy subscriber takes a second or so to register
        out = run(argv, place.env, cwd, case.stdin, case.stop_after, case.limit)
        observed = ""
        if observer is not None:
            try:
                seen, _ = observer.communicate(timeout=5)
            except subprocess.TimeoutExpired:
                seen, _ = _stop(observer)
            observed = seen.decode(errors="replace")
        return _places_masked(out.but(effects=_effects(case, place, cwd, observed)), cwd, place)
    finally:
        if observer is not None and observer.poll() is None:
            _stop(observer)
        if teardown is not None:
            teardown()


def _places_masked(out: Output, cwd: Path, place: Place) -> Output:
    """Paths of this machine replaced by names: the side's folder, the data, the corpus."""
    swaps = ((str(cwd), "<DIR>"), (str(place.data), "<DATA>"), (str(place.corpus), "<CORPUS>"))

    def mask(text: str) -> str:
        for path, name in swaps:
            text = text.replace(path, name)
        return text

    return out.but(stdout=mask(out.stdout), stderr=mask(out.stderr), effects=mask(out.effects))
