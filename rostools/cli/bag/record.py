"""``rostools bag record``: rosbag record to ``.bag`` or MCAP, with a live table on a terminal."""

from __future__ import annotations

import shutil
import sys
import time
from functools import partial
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rostools.bag.formats.model import counted
from rostools.cli import output
from rostools.cli.bag.options import (
    DistroOpt,
    OutputFile,
    Receiving,
    Splitting,
    TopicOptions,
    TypesOpt,
)
from rostools.cli.bag.shared import human_size
from rostools.cli.common import FormatOpt, node_session, output_format
from rostools.cli.declare import command
from rostools.cli.liveview import LiveView
from rostools.cli.output import Format, check_writable, render
from rostools.cli.units import parse_duration
from rostools.errors import DataLossError, UsageError, one_line

if TYPE_CHECKING:
    import asyncio
    from pathlib import Path

    from rostools.bag.live.recorder import Recorder, RecordOptions
    from rostools.node.node import LiveNode


def summary_data(rec: Recorder) -> dict[str, Any]:
    """What was recorded: files, and per topic its type, messages, bytes and drops."""
    data = {
        "files": [str(p) for p in rec.closed_files],
        "messages": sum(s.written for s in rec.stats.values()),
        "bytes": rec.written_bytes,
        "drops": rec.drops,
        "topics": {
            topic: {"type": s.type, "messages": s.written, "received": s.messages, "drops": s.drops}
            for topic, s in sorted(rec.stats.items())
        },
    }
    if rec.ros2 is not None:  # --to ros2: the topics left out, and why; messages that did not fit
        data["left_out"] = dict(sorted(rec.left_out.items()))
        data["unconverted"] = dict(sorted(rec.unconverted.items()))
    return data


def summary_text(data: dict[str, Any]) -> str:
    """The end-of-recording summary for people."""
    lines = [
        f"recorded {counted(data['messages'], 'message')} ({human_size(data['bytes'])}) on "
        f"{counted(len(data['topics']), 'topic')} into "
        f"{', '.join(data['files']) or 'no file'}"
    ]
    left_out, unconverted = data.get("left_out", {}), data.get("unconverted", {})
    for topic, t in data["topics"].items():
        drops = f", {t['drops']} DROPPED" if t["drops"] else ""
        if topic in left_out:
            drops += ", LEFT OUT (not convertible to ROS 2)"
        if unconverted.get(topic):
            drops += f", {unconverted[topic]} LEFT OUT (did not fit the type)"
        unit = "msg" if t["messages"] == 1 else "msgs"
        kind = one_line(t["type"] or "?")
        lines.append(f"  {one_line(topic)} [{kind}]: {t['messages']} {unit}{drops}")
    return "\n".join(lines)


class LiveTable(LiveView):
    """The terminal view: per topic messages, rate, bandwidth and drops; file size and disk."""

    def __init__(self) -> None:
        super().__init__()
        self.pubs: dict[str, int] = {}

    def tick(self, rec: Recorder) -> None:
        """Redraw, at most twice a second."""
        if not self.due():
            return
        self.pubs = {topic: rec.publishers(topic) for topic in rec.stats}
        self._draw(rec, time.monotonic())

    def last_frame(self, rec: Recorder) -> None:
        """The frame left on screen: what was written, and the publishers recorded from.

        By now the recorder has unsubscribed, so it has no publishers left to count.
        """
        self._draw(rec, time.monotonic())

    def _draw(self, rec: Recorder, now: float) -> None:
        self.measure(rec.stats, rec.started, now)
        self.live.update(self._table(rec, now), refresh=True)

    def _table(self, rec: Recorder, now: float) -> Any:
        from rich.markup import escape
        from rich.table import Table

        path = rec.current_file
        if path is not None and not path.exists() and rec.closed_files:
            path = rec.closed_files[-1]  # the last frame: the .active file has its name now
        size = _size(path) if path is not None and path.exists() else 0
        free = shutil.disk_usage(path.parent if path is not None else ".").free
        title = (
            f"recording {path.name if path else '…'}: {human_size(size)} written, "
            f"{human_size(free)} free, {now - rec.started:.0f} s"
        )
        table = Table(title=title, title_justify="left")
        for col in ("topic", "type", "pubs", "recorded", "rate", "bandwidth", "drops"):
            table.add_column(col, justify="left" if col in ("topic", "type") else "right")
        for topic, s in sorted(rec.stats.items()):
            hz, bw = self.rates.get(topic, (0.0, 0.0))
            drops = f"[bold red]{s.drops}[/]" if s.drops else "0"
            # names are the peers' and may hold markup ("[bold]") or control characters
            kind = escape(one_line(s.type)) if s.type else "[dim]no publisher yet[/]"
            pubs = str(self.pubs.get(topic, 0))
            name = escape(one_line(topic))
            table.add_row(
                name, kind, pubs, str(s.written), f"{hz:.1f} Hz", f"{human_size(bw)}/s", drops
            )
        return table


def _size(path: Path) -> int:
    """A file's size, or what the files of a folder (``--to ros2``'s) hold."""
    if path.is_dir():
        return sum(p.stat().st_size for p in path.iterdir() if p.is_file())
    return path.stat().st_size


@command()
def record(
    ctx: typer.Context,
    topics: Annotated[list[str] | None, typer.Argument(help="Topics (regexes with -e).")] = None,
    choice: TopicOptions = TopicOptions(),  # noqa: B008 - a record of options, never changed
    out: OutputFile = OutputFile(),  # noqa: B008
    splitting: Splitting = Splitting(),  # noqa: B008
    limit: Annotated[
        int | None, typer.Option("--limit", "-l", help="Stop after N messages per topic.")
    ] = None,
    buffer: Annotated[
        int,
        typer.Option(
            "--buffsize",
            "-b",
            help="Memory for messages waiting to be written, in MB; 0 for unlimited.",
        ),
    ] = 256,
    receiving: Receiving = Receiving(),  # noqa: B008
    publish: Annotated[
        bool,
        typer.Option("--publish", "-p", help="Announce each new file on begin_write (latched)."),
    ] = False,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="No live table.")] = False,
    to: Annotated[
        str,
        typer.Option(
            "--to", help="ros1: a .bag or MCAP file; ros2: a rosbag2 folder (MCAP of CDR)."
        ),
    ] = "ros1",
    distro: DistroOpt = None,
    types_file: TypesOpt = None,
    fmt: FormatOpt = None,
) -> None:
    """Record topics to a .bag or MCAP file (rosbag record), or a rosbag2 folder (--to ros2).

    Exit 6 on drops, a failed write, or a topic --to ros2 cannot convert.
    """
    target = _target(to, distro, types_file, out)
    opts = _record_options(topics or [], choice, out, splitting, limit, target)
    opts.types_file = str(types_file) if types_file is not None else None
    opts.buffer_bytes = max(buffer, 0) * 1024 * 1024
    opts.tcp_nodelay, opts.publish = receiving.tcp_nodelay, publish
    opts.min_space = receiving.min_space_bytes()
    check_writable(opts.base)  # before subscribing
    if opts.format == "ros2":
        _check_new_folder(opts.base)
    fmt = output_format(ctx, fmt)
    live = not quiet and fmt is Format.text and sys.stderr.isatty()
    rec = node_session(ctx, partial(_run, opts, live, quiet), "rostools_record")
    data = summary_data(rec)
    if fmt is Format.text:
        if not quiet:
            sys.stderr.write(summary_text(data) + "\n")
    else:
        output.put(render(fmt, data) + "\n")
    if losses := _losses(rec):
        raise DataLossError("; ".join(losses))


def _losses(rec: Recorder) -> list[str]:
    """What the recording lost, one phrase each: drops, and what ``--to ros2`` left out."""
    losses = []
    if rec.drops:
        were = "was" if rec.drops == 1 else "were"
        losses.append(f"{counted(rec.drops, 'message')} {were} dropped: the buffer (-b) was full")
    if rec.left_out:
        names = ", ".join(one_line(t) for t in sorted(rec.left_out))
        losses.append(f"{counted(len(rec.left_out), 'topic')} not convertible to ROS 2: {names}")
    if bad := sum(rec.unconverted.values()):
        names = ", ".join(one_line(t) for t in sorted(rec.unconverted))
        losses.append(f"{counted(bad, 'message')} did not fit its type, left out: {names}")
    return losses


def _check_new_folder(path: Path) -> None:
    """``--to ros2`` writes a new folder, as ros2 bag record: an existing one is refused."""
    from rostools.bag.live.bagfile import active_name

    if path.suffix.lower() in (".bag", ".mcap"):
        raise UsageError(f"--to ros2 records a rosbag2 folder: name it without {path.suffix}")
    for taken in (path, active_name(path)):
        if taken.exists():
            raise UsageError(f"{taken} exists; give another name (-O) or remove it")


def _target(to: str, distro: str | None, types_file: Path | None, out: OutputFile) -> str | None:
    """``--to ros2``'s distro, None for ``--to ros1``; checked, with the types file."""
    if to not in ("ros1", "ros2"):
        raise UsageError(f"unknown --to {to!r} (ros1 or ros2)")
    if to == "ros1":
        if distro is not None or types_file is not None:
            raise UsageError("--distro and --types are for --to ros2")
        return None
    if out.storage not in (None, "mcap") or out.bz2:
        raise UsageError("--to ros2 writes MCAP: --storage bag and --bz2 are for ROS 1 files")
    from rostools.bag.formats.ros2types import DEFAULT_DISTRO, DISTROS

    if distro is not None and distro not in DISTROS:
        raise UsageError(f"unknown ROS 2 distro {distro!r} (use one of {', '.join(DISTROS)})")
    if types_file is not None:
        from rostools.bag.formats.ros2types import load_rules

        load_rules(types_file)  # a malformed file is said now, before anything is recorded
    return distro or DEFAULT_DISTRO


def _record_options(
    topics: list[str],
    choice: TopicOptions,
    out: OutputFile,
    splitting: Splitting,
    limit: int | None,
    distro: str | None = None,
) -> RecordOptions:
    """The recorder's options from the command line's, checked as rosbag record checks them.

    ``distro``: ``--to ros2``'s, which writes a rosbag2 folder named as ``-O``/``-o`` say.
    """
    from rostools.bag.live.recorder import RecordOptions

    choice.check(topics)
    for value, flag in ((splitting.size, "--size"), (splitting.max_splits, "--max-splits"),
                        (limit, "-l")):  # fmt: skip
        if value is not None and value <= 0:
            raise UsageError(f"{flag} must be positive")
    path, kind = out.path() if distro is None else (out.folder(), "ros2")
    size, duration = splitting.size, splitting.duration
    opts = RecordOptions(
        **choice.choice(topics), base=path, format=kind,
        compression=out.chunk_compression("mcap" if distro else kind),
        chunk_size=out.chunk_bytes(), split=splitting.split,
        size=size * 1024 * 1024 if size else None,
        duration=parse_duration(duration, "--duration") if duration else None,
        max_splits=splitting.max_splits, repeat_latched=splitting.repeat_latched, limit=limit,
        dated=None if out.output_name is not None else (lambda now: out.path(now)[0]),
        distro=distro,
    )  # fmt: skip
    opts.check()
    return opts


async def _run(
    opts: RecordOptions, live: bool, quiet: bool, n: LiveNode, stop: asyncio.Event
) -> Recorder:
    """Record until stopped or a limit is reached: with the live table, or lines on stderr."""
    from rostools.bag.live.recorder import Recorder

    rec = Recorder(n, opts)
    rec.check_disk(started=False)  # before saying "Recording to"
    if not live:
        if not quiet:
            rec.on_subscribe = _say_subscribing
            sys.stderr.write(f"Recording to '{opts.base}'.\n")
        await rec.run(stop)
        return rec
    with LiveTable() as table:
        await rec.run(stop, table.tick)
        table.last_frame(rec)
    return rec


def _say_subscribing(topic: str) -> None:
    sys.stderr.write(f"Subscribing to {one_line(topic)}\n")
    sys.stderr.flush()
