"""What the bag commands share, and no command owns.

Time windows, renames, notes, progress, and the report of a copy. Typer-free.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from rostools.bag.formats.model import counted
from rostools.cli import output
from rostools.cli.output import Format, emit, render
from rostools.errors import one_line

if TYPE_CHECKING:
    from rostools.bag.formats import mcap_format
    from rostools.bag.formats.base import BagReader
    from rostools.bag.tools.ops import CopyReport
    from rostools.bag.tools.recover import RecoverReport
    from rostools.bag.tools.rename import Renames


def time_window(
    paths: list[Path], start: float | None, end: float | None
) -> tuple[int | None, int | None]:
    """``--start``/``--end`` as ns bounds, counted from the earliest start among ``paths``."""
    if start is None and end is None:
        return None, None
    from rostools.bag.formats.access import bag_info

    begin = min(bag_info(p).start_ns or 0 for p in paths)
    lo = None if start is None else begin + (seconds_to_ns(start) or 0)
    hi = None if end is None else begin + (seconds_to_ns(end) or 0)
    return lo, hi


def renames(topics: list[str] | None, types: list[str] | None) -> Renames | None:
    """The rules of ``--rename`` and ``--rename-type``, or None when there are none."""
    from rostools.bag.tools.rename import Renames

    return Renames.parse(topics or [], types or []) or None


def say_note(note: str) -> None:
    """How an input had to be read (an index that disagrees, a scan): a ``note:`` line."""
    sys.stderr.write(f"note: {note}\n")


def say_notes(notes: Iterable[str]) -> None:
    """``say_note`` for each."""
    for note in notes:
        say_note(note)


def check_read(readers: Sequence[BagReader], done: str, unindexed_fails: bool = False) -> None:
    """After a command read these bags: say their notes, and exit 6 if anything was left out.

    ``done`` says what the command did, for the error line. With ``unindexed_fails``, a bag
    read without its index is exit 1 (``bag info``, as rosbag info).
    """
    from rostools.bag.formats.base import after_reading

    after_reading(readers, done, say_note, unindexed_fails=unindexed_fails)


class Progress:
    """A progress bar on a terminal (stderr), NDJSON with ``--format json``, else nothing."""

    def __init__(self, label: str, fmt: Format, quiet: bool) -> None:
        self.label = label
        self.json = fmt is Format.json
        self.bar = not quiet and not self.json and sys.stderr.isatty()
        self.last = -1

    def __call__(self, done: int, total: int) -> None:
        """Messages copied so far, of ``total``."""
        percent = int(100 * done / total) if total else 100
        if percent == self.last:
            return
        self.last = percent
        if self.json:
            output.write(Format.json, {"progress": self.label, "done": done, "total": total})
        elif self.bar:
            width = 30
            filled = width * percent // 100
            sys.stderr.write(
                f"\r{self.label} [{'#' * filled}{'.' * (width - filled)}] {percent:3d}%"
            )
            sys.stderr.flush()

    def done(self) -> None:
        """End the bar's line."""
        if self.bar:
            sys.stderr.write("\n")


def _report(fmt: Format, report: CopyReport) -> None:
    data = {
        "source": str(report.source),
        "output": str(report.output),
        "format": report.format,
        "compression": report.compression,
        "messages_read": report.messages_read,
        "messages_written": report.messages_written,
        "connections": report.connections,
        "extras_copied": report.extras_copied,
        "extras_left_out": report.extras_left_out,
    }
    if report.notes or report.lost:
        data.update(notes=list(report.notes), lost=list(report.lost))
    if fmt is Format.text:
        sys.stderr.write(
            f"wrote {report.messages_written} of {counted(report.messages_read, 'message')} to "
            f"{report.output} ({report.format}, {report.compression})\n"
        )
        say_notes(report.notes)
        if report.extras_left_out:
            sys.stderr.write(
                f"left out {counted(report.extras_left_out, 'MCAP attachment/metadata record')}: "
                + (
                    "a .bag has no place for them\n"
                    if report.format == "bag"
                    else "outside the time range\n"
                )
            )
    elif fmt is Format.json:
        output.write(fmt, data)  # the last record of the NDJSON progress stream
    else:
        emit(fmt, data)


def copy_command(
    fmt: Format,
    quiet: bool,
    label: str,
    run: Callable[[Any], CopyReport],
    check: bool = True,
    say: bool = True,
) -> CopyReport:
    """Run a copying command with a progress bar, then report what it wrote.

    With ``check``, exit 6 if the input had damage that was left out; without ``say``, the
    text report's lines are left out (``compress -q`` prints nothing, as rosbag's).
    """
    progress = Progress(label, fmt, quiet)
    try:
        report = run(progress)
    finally:
        progress.done()
    if say or fmt is not Format.text:
        _report(fmt, report)
    if check:
        report.raise_if_lost()
    return report


def seconds_to_ns(value: float | None) -> int | None:
    """Seconds as ns, rounded (None stays None)."""
    return None if value is None else round(value * 1e9)


def recovered_name(src: Path) -> Path:
    """Where ``recover`` writes by default.

    ``x.bag.active`` becomes ``x.bag`` (the name the recorder would have given it), ``x.bag``
    becomes ``x.recovered.bag`` and ``x.mcap`` becomes ``x.recovered.mcap``.
    """
    if src.name.endswith(".active"):
        final = src.with_name(src.name.removesuffix(".active"))
        if not final.exists():
            return final
        src = final
    suffix = src.suffix or ".bag"
    return src.with_name(src.name.removesuffix(suffix) + ".recovered" + suffix)


def human_size(size: float) -> str:
    """rosbag's 1024-based sizes, always in KB or more."""
    for suffix in ("KB", "MB", "GB", "TB", "PB", "EB", "ZB", "YB"):
        size /= 1024.0
        if size < 1024.0:
            return f"{size:.1f} {suffix}"
    return "-"


def recover_report(fmt: Format, report: RecoverReport, quiet: bool = False) -> None:
    """What ``recover`` and ``reindex`` say of one rebuilt bag: a document, or notes and a line."""
    if fmt is not Format.text:
        data = {
            "source": str(report.source), "output": str(report.output), "format": report.format,
            "was_indexed": report.was_indexed, "messages": report.messages,
            "connections": report.connections, "notes": list(report.notes),
            "lost": list(report.lost),
        }  # fmt: skip
        output.put(render(fmt, data) + "\n")
    elif not quiet:
        for note in report.notes:
            sys.stderr.write(f"note: {one_line(note)}\n")  # may quote the file's names
        sys.stderr.write(f"recovered {counted(report.messages, 'message')} into {report.output}\n")


def extras_of(path: Path) -> list[mcap_format.Attachment | mcap_format.Metadata]:
    """An MCAP file's attachments and metadata records, in file order (a ``.bag`` has none)."""
    from rostools.bag.formats.access import open_bag
    from rostools.bag.formats.mcap_reader import McapReader

    with open_bag(path) as bag:
        return bag.extras() if isinstance(bag, McapReader) else []
