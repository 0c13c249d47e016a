"""``rostools bag snapshot``: a dash cam, the last minutes in memory.

It buffers topics and writes a file when triggered: ``trigger_snapshot`` (rosbag_snapshot's
service), ``~trigger``, SIGUSR1, or the ``s`` key. ``bag trigger`` (``trigger.py``) is the
client of ``trigger_snapshot``.
"""

from __future__ import annotations

import signal
import sys
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rostools.bag.formats.model import counted
from rostools.cli.bag.options import Buffering, OutputFile, Receiving, TopicOptions
from rostools.cli.common import FormatOpt, node_session, output_format
from rostools.cli.declare import command
from rostools.cli.output import Format, check_writable, write
from rostools.cli.units import parse_duration
from rostools.errors import DataLossError, RostoolsError, UsageError, one_line

if TYPE_CHECKING:
    import asyncio

    from rostools.bag.live.snapshot import SnapshotOptions, Snapshotter
    from rostools.bag.live.snapshot_job import SnapshotJob
    from rostools.node.node import LiveNode

MB = 1024 * 1024


@command()
def snapshot(
    ctx: typer.Context,
    topics: Annotated[list[str] | None, typer.Argument(help="Topics (regexes with -e).")] = None,
    choice: TopicOptions = TopicOptions(),  # noqa: B008 - a record of options, never changed
    buffering: Buffering = Buffering(),  # noqa: B008
    out: OutputFile = OutputFile(),  # noqa: B008
    receiving: Receiving = Receiving(),  # noqa: B008
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="No live table or lines.")] = False,
    fmt: FormatOpt = None,
) -> None:
    """Keep the last --duration of topics in memory; write them to a bag when triggered.

    Triggers: the trigger_snapshot service (rosbag_snapshot's; 'rostools bag trigger'),
    ~trigger (std_srvs/Trigger), SIGUSR1, and the s key. ~pause and ~resume (and the p and r
    keys) stop and restart buffering. Exit 6 if a file could not be written whole, or lost
    messages of its window (each file's line says how many).
    """
    opts = snapshot_options(topics or [], choice, buffering, out, receiving)
    check_writable(opts.base)
    fmt = output_format(ctx, fmt)
    snap = node_session(ctx, partial(_buffer, opts=opts, out=fmt, quiet=quiet), "rostools_snapshot")
    from rostools.cli.bag.snapview import stopped_data, stopped_text

    data = stopped_data(snap)
    if fmt is not Format.text:
        write(fmt, {"event": "stopped", **data})
    elif not quiet:
        _line(stopped_text(data))
    if snap.failed or snap.lossy:
        bad = [job for job in snap.finished if job.error is not None or job.lost]
        names = ", ".join(
            one_line(job.path) + (f" ({job.lost} lost)" if job.error is None else "") for job in bad
        )
        raise DataLossError(
            f"{counted(snap.failed + snap.lossy, 'snapshot')} not written whole: {names}"
        )


def snapshot_options(
    topics: list[str],
    choice: TopicOptions,
    buffering: Buffering,
    out: OutputFile,
    receiving: Receiving,
) -> SnapshotOptions:
    """The library's options; ``UsageError`` for values that do not go together.

    Unlike record, ``-x`` alone buffers every topic but those (as rosbag_snapshot's exclude).
    """
    from rostools.bag.live.snapshot import SnapshotOptions

    if not (topics or choice.all_ or choice.node or choice.exclude or choice.types):
        raise UsageError("give topics to buffer, or -a, -e REGEX, --topic-types or --node NAME")
    if choice.all_ and topics:
        raise UsageError("-a buffers every topic; do not also name topics")
    for value, flag in ((buffering.size, "--size"), (buffering.topic_size, "--topic-size")):
        if value is not None and value <= 0:
            raise UsageError(f"{flag} must be positive")
    path, kind = out.path()
    prefix = ""
    if out.output_name is None:  # the dated name is made anew for each file
        given = Path(out.output_prefix or "")
        prefix = given.stem if given.suffix.lower() in (".bag", ".mcap") else given.name
        path = path.with_name("snapshot." + kind)  # only its folder counts
    before, after = buffering.before, buffering.after
    opts = SnapshotOptions(
        **choice.choice(topics), base=path, format=kind,
        name=path.name if out.output_name is not None else None, prefix=prefix,
        compression=out.chunk_compression(kind), chunk_size=out.chunk_bytes(),
        tcp_nodelay=receiving.tcp_nodelay, min_space=receiving.min_space_bytes(),
        duration=parse_duration(buffering.duration, "--duration"), size=buffering.size * MB,
        topic_size=(buffering.topic_size or 0) * MB, clear_on_write=buffering.clear_on_write,
        max_writes=buffering.max_writes,
        before=parse_duration(before, "--before") if before else None,
        after=parse_duration(after, "--after") if after else 0.0,
    )  # fmt: skip
    opts.check()
    return opts


async def _buffer(
    node: LiveNode, stop: asyncio.Event, *, opts: SnapshotOptions, out: Format, quiet: bool
) -> Snapshotter:
    """Run the snapshot recorder with its triggers: a signal, keys, and what it shows."""
    import asyncio

    from rostools.bag.live.snapshot import Snapshotter
    from rostools.cli.bag.keys import keyboard
    from rostools.cli.bag.snapview import SnapshotTable

    snap = Snapshotter(node, opts)
    snap.check_disk(started=False)
    live = not quiet and out is Format.text and sys.stderr.isatty()
    table = SnapshotTable() if live else None
    snap.on_started = lambda job: _started(job, out, quiet or live)
    snap.on_written = lambda job: _written(job, out, quiet, table)

    def local() -> None:
        try:
            snap.trigger(snap.local_request(), remote=False)
        except RostoolsError as err:
            _line(f"no snapshot: {err}")

    loop = asyncio.get_running_loop()
    keys = {"s": local, "p": lambda: snap.set_paused(True), "r": lambda: snap.set_paused(False)}
    loop.add_signal_handler(signal.SIGUSR1, local)
    try:
        with keyboard(keys if live else {}, loop):
            if table is None:
                if not quiet and out is Format.text:
                    snap.on_subscribe = lambda topic: _line(f"Buffering {one_line(topic)}")
                await snap.run(stop)
                return snap
            with table:
                await snap.run(stop, table.tick)
                table.tick(snap, force=True)
    finally:
        loop.remove_signal_handler(signal.SIGUSR1)
    return snap


def _line(text: str) -> None:
    sys.stderr.write(one_line(text) + "\n")
    sys.stderr.flush()


def _started(job: SnapshotJob, out: Format, silent: bool) -> None:
    if out is not Format.text:
        write(out, {"event": "writing", "name": str(job.path)})
    elif not silent:
        _line(f"writing {job.path}")


def _written(job: SnapshotJob, out: Format, quiet: bool, table: Any) -> None:
    """A file is complete: a line (or an NDJSON record); a failure is one line, and goes on."""
    from rostools.bag.live.bagfile import write_failure
    from rostools.cli import report
    from rostools.cli.bag.snapview import written_text

    summary = job.summary()
    if job.error is not None:
        report(write_failure(job.error, "that snapshot stopped; buffering goes on"), False)
    if out is not Format.text:
        write(out, {"event": "written", **summary})
    elif table is not None:
        table.written(job)
    elif not quiet and job.error is None:
        _line(written_text(summary))
