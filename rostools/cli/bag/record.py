"""``rostools bag record``: rosbag record to ``.bag`` or MCAP, with a live table on a terminal."""

from __future__ import annotations

import shutil
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rostools.bag.access import WRITE_COMPRESSIONS
from rostools.bag.model import counted
from rostools.cli.common import FormatOpt, node_session, output_format
from rostools.cli.declare import command
from rostools.cli.output import Format, check_writable, render
from rostools.cli.units import parse_duration, parse_size
from rostools.errors import DataLossError, UsageError, one_line

if TYPE_CHECKING:
    import asyncio

    from rostools.bag.record import Recorder
    from rostools.node.node import Node


def output_name(
    name: str | None, prefix: str | None, storage: str | None, now: float | None = None
) -> tuple[Path, str]:
    """The file to write and its format, from ``-O``, ``-o`` and ``--storage``.

    As rosbag: ``-O x`` writes ``x.bag``; ``-o p`` writes ``p_<date-time>.bag``; neither
    writes ``<date-time>.bag``. A name ending in ``.mcap`` means MCAP, as ``--storage mcap`` does.
    """
    if name is not None and prefix is not None:
        raise UsageError("-O and -o cannot be combined")
    given = name if name is not None else prefix
    suffix = Path(given).suffix.lower() if given else ""
    storage = storage or ("mcap" if suffix == ".mcap" else "bag")
    if storage not in ("bag", "mcap"):
        raise UsageError(f"unknown --storage {storage!r} (bag or mcap)")
    ext = "." + storage
    if suffix in (".bag", ".mcap"):
        given = given[: -len(suffix)] if given else given
    if name is not None:
        return Path(name if suffix == ext else f"{given}{ext}"), storage
    stamp = time.strftime("%Y-%m-%d-%H-%M-%S", time.localtime(now))
    if prefix is not None:
        return Path(f"{given}_{stamp}{ext}"), storage
    return Path(stamp + ext), storage


def compression_choice(storage: str, bz2: bool, lz4: bool, compression: str | None) -> str | None:
    """The chunk compression from ``--bz2``/``--lz4``/``--compression`` (None: the default)."""
    chosen = [c for c, on in (("bz2", bz2), ("lz4", lz4), (compression, compression)) if on]
    if len(set(chosen)) > 1:
        raise UsageError("give one compression: --bz2, --lz4 or --compression")
    allowed = WRITE_COMPRESSIONS[storage]
    if chosen and chosen[0] not in allowed:
        raise UsageError(f"{storage} files cannot use {chosen[0]} (use {', '.join(allowed)})")
    return chosen[0] if chosen else None


def _size(n: float) -> str:
    for unit in ("B", "KB", "MB", "GB"):
        if abs(n) < 1024 or unit == "GB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1024
    return f"{n:.1f} TB"


def summary_data(rec: Recorder) -> dict[str, Any]:
    """What was recorded: files, and per topic its type, messages, bytes and drops."""
    return {
        "files": [str(p) for p in rec.closed_files],
        "messages": sum(s.written for s in rec.stats.values()),
        "bytes": rec.written_bytes,
        "drops": rec.drops,
        "topics": {
            topic: {"type": s.type, "messages": s.written, "received": s.messages, "drops": s.drops}
            for topic, s in sorted(rec.stats.items())
        },
    }


def summary_text(data: dict[str, Any]) -> str:
    """The end-of-recording summary for people."""
    lines = [
        f"recorded {counted(data['messages'], 'message')} ({_size(data['bytes'])}) on "
        f"{counted(len(data['topics']), 'topic')} into "
        f"{', '.join(data['files']) or 'no file'}"
    ]
    for topic, t in data["topics"].items():
        drops = f", {t['drops']} DROPPED" if t["drops"] else ""
        unit = "msg" if t["messages"] == 1 else "msgs"
        kind = one_line(t["type"] or "?")
        lines.append(f"  {one_line(topic)} [{kind}]: {t['messages']} {unit}{drops}")
    return "\n".join(lines)


class LiveTable:
    """The terminal view: per topic messages, rate, bandwidth and drops; file size and disk."""

    def __init__(self) -> None:
        from rich.console import Console
        from rich.live import Live

        self.live = Live(console=Console(stderr=True), auto_refresh=False, transient=False)
        self.last: dict[str, tuple[float, int, int]] = {}
        self.rates: dict[str, tuple[float, float]] = {}
        self.pubs: dict[str, int] = {}
        self.next_draw = 0.0

    def __enter__(self) -> LiveTable:
        self.live.__enter__()
        return self

    def __exit__(self, *exc: object) -> None:
        self.live.__exit__(None, None, None)

    def tick(self, rec: Recorder) -> None:
        """Redraw, at most twice a second."""
        now = time.monotonic()
        if now < self.next_draw:
            return
        self.next_draw = now + 0.5
        self.pubs = {topic: rec.publishers(topic) for topic in rec.stats}
        self._draw(rec, now)

    def last_frame(self, rec: Recorder) -> None:
        """The frame left on screen: what was written, and the publishers recorded from.

        By now the recorder has unsubscribed, so it has no publishers left to count.
        """
        self._draw(rec, time.monotonic())

    def _draw(self, rec: Recorder, now: float) -> None:
        for topic, s in rec.stats.items():
            t0, m0, b0 = self.last.get(topic, (rec.started, 0, 0))
            if now - t0 >= 1.0:
                self.rates[topic] = ((s.messages - m0) / (now - t0), (s.bytes - b0) / (now - t0))
                self.last[topic] = (now, s.messages, s.bytes)
        self.live.update(self._table(rec, now), refresh=True)

    def _table(self, rec: Recorder, now: float) -> Any:
        from rich.markup import escape
        from rich.table import Table

        path = rec.current_file
        if path is not None and not path.exists() and rec.closed_files:
            path = rec.closed_files[-1]  # the last frame: the .active file has its name now
        size = path.stat().st_size if path is not None and path.exists() else 0
        free = shutil.disk_usage(path.parent if path is not None else ".").free
        title = (
            f"recording {path.name if path else '…'}: {_size(size)} written, "
            f"{_size(free)} free, {now - rec.started:.0f} s"
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
            table.add_row(name, kind, pubs, str(s.written), f"{hz:.1f} Hz", f"{_size(bw)}/s", drops)
        return table


@command()
def record(
    ctx: typer.Context,
    topics: Annotated[list[str] | None, typer.Argument(help="Topics (regexes with -e).")] = None,
    all_: Annotated[bool, typer.Option("--all", "-a", help="Record every topic.")] = False,
    regex: Annotated[
        bool, typer.Option("--regex", "-e", help="The topics are regexes (full match).")
    ] = False,
    exclude: Annotated[
        list[str] | None,
        typer.Option("--exclude", "-x", help="Leave out topics matching this regex (repeatable)."),
    ] = None,
    node: Annotated[
        str | None, typer.Option("--node", help="Record what this node subscribes to.")
    ] = None,
    types: Annotated[
        list[str] | None,
        typer.Option("--topic-types", help="Also topics of these types (globs: sensor_msgs/*)."),
    ] = None,
    exclude_types: Annotated[
        list[str] | None,
        typer.Option("--exclude-topic-types", help="Never topics of these types (globs)."),
    ] = None,
    output_name_: Annotated[
        str | None, typer.Option("--output-name", "-O", help="The file name (.bag added).")
    ] = None,
    output_prefix: Annotated[
        str | None, typer.Option("--output-prefix", "-o", help="A prefix for a dated file name.")
    ] = None,
    storage: Annotated[
        str | None,
        typer.Option(
            "--storage", "-s", help="File format: bag or mcap (default: from -O, else bag)."
        ),
    ] = None,
    split: Annotated[
        bool, typer.Option("--split", help="Start a new file at --size or --duration.")
    ] = False,
    size: Annotated[
        int | None, typer.Option("--size", help="Stop (or split) at this many MB.")
    ] = None,
    duration: Annotated[
        str | None, typer.Option("--duration", help="Stop (or split) after 30, 30s, 5m, 2h.")
    ] = None,
    max_splits: Annotated[
        int | None,
        typer.Option(
            "--max-splits",
            help="Keep only the newest N closed split files, and the last (rosbag: N + 1 in all).",
        ),
    ] = None,
    repeat_latched: Annotated[
        bool,
        typer.Option("--repeat-latched", help="Copy latched messages into every split file."),
    ] = False,
    limit: Annotated[
        int | None, typer.Option("--limit", "-l", help="Stop after N messages per topic.")
    ] = None,
    bz2: Annotated[bool, typer.Option("--bz2", "-j", help="bz2 chunks (.bag).")] = False,
    lz4: Annotated[bool, typer.Option("--lz4", help="lz4 chunks (.bag or MCAP).")] = False,
    compression: Annotated[
        str | None,
        typer.Option("--compression", help="none, bz2, lz4 (.bag); zstd, lz4, none (MCAP)."),
    ] = None,
    chunk_size: Annotated[
        int | None, typer.Option("--chunksize", help="Chunk size in KB (default 768).")
    ] = None,
    buffer: Annotated[
        int,
        typer.Option(
            "--buffsize",
            "-b",
            help="Memory for messages waiting to be written, in MB; 0 for unlimited.",
        ),
    ] = 256,
    tcp_nodelay: Annotated[
        bool, typer.Option("--tcpnodelay", help="Ask publishers for TCP_NODELAY.")
    ] = False,
    min_space: Annotated[
        str,
        typer.Option(
            "--min-space", "-L", help="Stop when the disk has less free: 1G, 500M, 64K, 0 (off)."
        ),
    ] = "100M",
    publish: Annotated[
        bool,
        typer.Option("--publish", "-p", help="Announce each new file on begin_write (latched)."),
    ] = False,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="No live table.")] = False,
    fmt: FormatOpt = None,
) -> None:
    """Record topics to a .bag or MCAP file (rosbag record); exit 6 on drops or a failed write."""
    from rostools.bag.record import Recorder, RecordOptions

    topics = topics or []
    if not (topics or all_ or node or types):
        hint = "-x subtracts from -a or -e" if exclude else None
        raise UsageError(
            "give topics to record, or -a, -e REGEX, --topic-types or --node NAME", hint=hint
        )
    if all_ and topics:
        raise UsageError("-a records every topic; do not also name topics")
    for value, flag in ((size, "--size"), (max_splits, "--max-splits"), (limit, "-l")):
        if value is not None and value <= 0:
            raise UsageError(f"{flag} must be positive")
    path, kind = output_name(output_name_, output_prefix, storage)
    opts = RecordOptions(
        topics=topics, all=all_, regex=regex, exclude=exclude or [], node=node, base=path,
        types=types or [], exclude_types=exclude_types or [],
        format=kind, compression=compression_choice(kind, bz2, lz4, compression),
        chunk_size=chunk_size * 1024 if chunk_size else None, split=split,
        size=size * 1024 * 1024 if size else None,
        duration=parse_duration(duration, "--duration") if duration else None,
        max_splits=max_splits,
        repeat_latched=repeat_latched, limit=limit, tcp_nodelay=tcp_nodelay,
        buffer_bytes=max(buffer, 0) * 1024 * 1024, min_space=parse_size(min_space, "-L"),
        publish=publish,
    )  # fmt: skip
    opts.check()
    check_writable(opts.base)  # before subscribing
    out = output_format(ctx, fmt)
    live = not quiet and out is Format.text and sys.stderr.isatty()

    async def main(n: Node, stop: asyncio.Event) -> Recorder:
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

    rec = node_session(ctx, main, "rostools_record")
    data = summary_data(rec)
    if out is Format.text:
        if not quiet:
            sys.stderr.write(summary_text(data) + "\n")
    else:
        sys.stdout.write(render(out, data) + "\n")
    if rec.drops:
        were = "was" if rec.drops == 1 else "were"
        raise DataLossError(
            f"{counted(rec.drops, 'message')} {were} dropped: the buffer (-b) was full"
        )


def _say_subscribing(topic: str) -> None:
    sys.stderr.write(f"Subscribing to {one_line(topic)}\n")
    sys.stderr.flush()
