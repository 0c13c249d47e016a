"""``bag split``: one bag into parts by duration, size, message count or given times.

Parts are named as ``record --split`` names its files (``NAME_0.bag``, ``NAME_1.bag``, ...),
and streamed: one part is open at a time. Without ``repeat_latched`` every message goes to
exactly one part, so merging the parts gives the bag back, message for message. Library code:
no printing.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from rostools.bag.formats.access import (
    file_name,
    format_for_name,
    mcap_profile,
    open_bag,
    open_writer,
    require_ros1,
)
from rostools.bag.formats.base import BagWriter, Targets, problems
from rostools.bag.formats.model import BagUsageError, Connection, counted, lost_data
from rostools.bag.tools.ops import compile_filter
from rostools.bag.tools.options import ALL, PROGRESS_EVERY, CopyOptions, Progress


@dataclass
class Part:
    """One written part: its file, message count and first and last times (ns)."""

    path: Path
    messages: int = 0
    start_ns: int = 0
    end_ns: int = 0


@dataclass
class SplitReport:
    """What a split wrote."""

    source: Path
    parts: list[Part] = field(default_factory=list)
    #: How the source had to be read, and what of it could not be (``BagReader``).
    notes: tuple[str, ...] = ()
    lost: tuple[str, ...] = ()

    def raise_if_lost(self) -> None:
        """Raise ``BagDataLossError`` (exit code 6) naming what was left out, if anything."""
        if self.lost:
            written = sum(p.messages for p in self.parts)
            raise lost_data(
                f"wrote {counted(written, 'message')} in {counted(len(self.parts), 'part')}",
                self.lost,
            )


@dataclass(frozen=True)
class Cut:
    """Where parts end: exactly one of the four is set (times in ns, sizes in bytes)."""

    duration_ns: int | None = None
    size: int | None = None
    count: int | None = None
    at_ns: Sequence[int] = ()

    def check(self) -> None:
        """One rule, and a sensible one."""
        given = [self.duration_ns is not None, self.size is not None, self.count is not None,
                 bool(self.at_ns)]  # fmt: skip
        if sum(given) != 1:
            raise BagUsageError("give one of --duration, --size, --count or --at")
        for value, flag in ((self.duration_ns, "--duration"), (self.size, "--size"),
                            (self.count, "--count")):  # fmt: skip
            if value is not None and value <= 0:
                raise BagUsageError(f"{flag} must be above 0")


class _Splitter:
    """Decides, message by message, whether a new part begins."""

    def __init__(self, cut: Cut, bag_start: int) -> None:
        self.cut = cut
        self.bag_start = bag_start
        self.bounds = sorted(cut.at_ns)
        self.next_bound = 0  # index into bounds
        self.slot = 0  # duration: the part's slot since the bag's start

    def new_part(self, t: int, part: Part, part_bytes: int) -> bool:
        """Whether the message at ``t`` starts a new part after ``part``."""
        cut = self.cut
        if cut.count is not None:
            return part.messages >= cut.count
        if cut.size is not None:
            return part_bytes >= cut.size
        if cut.duration_ns is not None:
            slot = (t - self.bag_start) // cut.duration_ns
            if slot != self.slot:
                self.slot = slot
                return True
            return False
        crossed = False
        while self.next_bound < len(self.bounds) and t >= self.bounds[self.next_bound]:
            self.next_bound += 1
            crossed = True
        return crossed


class _Parts:
    """The part being written, and what starts the next one."""

    def __init__(
        self, base: Path, kind: str, report: SplitReport, splitter: _Splitter, repeat: bool
    ) -> None:
        self.base, self.kind, self.report, self.splitter = base, kind, report, splitter
        #: ``repeat_latched``: the last message of each latched connection, for the next part.
        self.latched: dict[int, tuple[Connection, memoryview]] | None = {} if repeat else None
        #: How parts are written, and the MCAP profile.
        self.writing: tuple[CopyOptions, Any] = (ALL, None)
        self.writer: BagWriter | None = None
        self.targets: Targets | None = None
        self.part = Part(file_name(base, True, 0))
        self.part_bytes = 0

    def write(self, conn: Connection, t: int, data: memoryview) -> None:
        """Write one message into the part it belongs in, starting that part if need be."""
        if self.writer is not None and self.splitter.new_part(t, self.part, self.part_bytes):
            self.writer.close()
            self.writer = None
        if self.writer is None:
            self._start(t)
        assert self.writer is not None and self.targets is not None
        self.writer.write(self.targets.resolve(conn), t, data)
        self.part.messages += 1
        self.part.end_ns = t
        self.part_bytes += len(data)
        if self.latched is not None and conn.latching:
            self.latched[conn.id] = (conn, data)

    def _start(self, t: int) -> None:
        """Open the next part at time ``t``; it starts with the latched messages so far."""
        options, profile = self.writing
        parts = self.report.parts
        self.part = Part(file_name(self.base, True, len(parts)), start_ns=t)
        parts.append(self.part)
        self.writer = open_writer(self.part.path, self.kind, options.compression,
                                  options.chunk_size, overwrite=options.overwrite,
                                  profile=profile)  # fmt: skip
        self.targets = Targets(self.writer, (), options.renames)
        self.part_bytes = 0
        if self.latched and len(parts) > 1:
            for old, payload in self.latched.values():
                self.writer.write(self.targets.resolve(old), t, payload)
                self.part.messages += 1

    def close(self) -> None:
        """Close the last part."""
        if self.writer is not None:
            self.writer.close()

    def abort(self) -> None:
        """Give up the part being written."""
        if self.writer is not None:
            self.writer.abort()


def split(
    src: str | Path,
    base: str | Path,
    cut: Cut,
    options: CopyOptions = ALL,
    *,
    repeat_latched: bool = False,
    progress: Progress | None = None,
) -> SplitReport:
    """Write ``src``'s messages into parts named after ``base`` (its suffix picks the format).

    ``repeat_latched``: each part after the first starts with the last message so far of every
    latched connection, stamped at the part's first message, as ``record --split`` does.
    ``options`` select and rename as for ``ops.filter_bag``; a part holds what they keep.
    """
    cut.check()
    src, base = Path(src), Path(base)
    kind = format_for_name(base)
    first = file_name(base, True, 0)
    if first.exists() and not options.overwrite:
        raise BagUsageError(f"{first} exists (use -f to overwrite)")
    report = SplitReport(src)
    keep = compile_filter(options.expression) if options.expression else None
    with open_bag(src, check_crcs=options.check_crcs) as reader:
        if kind != "mcap" or keep:  # an MCAP output takes any encoding as it is
            require_ros1(reader, "bag split", options.topics)
        info = reader.info()
        parts = _Parts(base, kind, report, _Splitter(cut, info.start_ns or 0), repeat_latched)
        profile = mcap_profile([reader], options.topics)
        parts.writing = (options, profile)
        read = 0
        try:
            for conn, t, data in reader.messages(
                topics=options.topics, start=options.start, end=options.end
            ):
                if keep is None or keep(conn, t, data):
                    parts.write(conn, t, data)
                read += 1
                if progress is not None and read % PROGRESS_EVERY == 0:
                    progress(read, info.message_count)
        except BaseException:
            parts.abort()
            raise
        parts.close()
        report.notes, report.lost = problems([reader])
    if progress is not None:
        progress(read, info.message_count)
    return report
