"""The arguments and options the bag commands share.

Typer's: the commands import them for their annotations.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rostools.cli.common import FINITE, NoCrcCheckOpt
from rostools.cli.declare import options_record
from rostools.errors import UsageError

if TYPE_CHECKING:
    from rostools.bag.live.player import PlayOptions
    from rostools.bag.tools.options import CopyOptions
    from rostools.bag.tools.rename import Renames

BagArg = Annotated[Path, typer.Argument(help="A .bag or .mcap file.")]
OutArg = Annotated[Path, typer.Argument(help="The file to write; its name picks the format.")]
#: ``--distro`` of the commands that write ROS 2 (``convert`` and ``record`` with ``--to ros2``).
DistroOpt = Annotated[
    str | None,
    typer.Option("--distro", help="--to ros2: the ROS 2 release whose types to write (lyrical)."),
]
#: ``--types`` of the commands that write ROS 2: renames and definitions of the user's.
TypesOpt = Annotated[
    Path | None,
    typer.Option("--types", help="--to ros2: a YAML file of type renames and definitions."),
]
ForceOpt = Annotated[bool, typer.Option("--force", "-f", help="Overwrite an existing output file.")]
QuietOpt = Annotated[bool, typer.Option("--quiet", "-q", help="No progress bar.")]
CompressionOpt = Annotated[
    str | None,
    typer.Option(
        "--compression",
        "-c",
        help="Chunk compression: none, bz2 or lz4 (.bag); zstd, lz4 or none (MCAP).",
    ),
]
TopicsOpt = Annotated[list[str] | None, typer.Option("--topics", "-t", help="Only these topics.")]
StartOpt = Annotated[
    float | None,
    typer.Option("--start", click_type=FINITE, help="Seconds from the (earliest) bag's start."),
]
EndOpt = Annotated[
    float | None,
    typer.Option("--end", click_type=FINITE, help="Seconds from the (earliest) bag's start."),
]
FilterExprOpt = Annotated[
    str | None,
    typer.Option("--filter", help="Only messages for which this is true (as bag filter)."),
]


RenameOpt = Annotated[
    list[str] | None,
    typer.Option("--rename", help="Write topic OLD as NEW (/old:=/new, as play); repeatable."),
]
RenameTypeOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--rename-type",
        help="Rename a type (pkg/Old:=pkg/New) where its md5sum stays the same; repeatable.",
    ),
]


OutputDirOpt = Annotated[
    Path | None, typer.Option("--output-dir", help="Write here instead of replacing the bag.")
]


DstOpt = Annotated[Path | None, typer.Argument(help="Output (default: NAME.recovered.bag|mcap).")]


@options_record
@dataclass
class TopicOptions:
    """Which topics a live recorder takes besides those it names (bag record, bag snapshot)."""

    all_: Annotated[bool, typer.Option("--all", "-a", help="Every topic.")] = False
    regex: Annotated[
        bool, typer.Option("--regex", "-e", help="The topics are regexes (full match).")
    ] = False
    exclude: Annotated[
        list[str] | None,
        typer.Option("--exclude", "-x", help="Leave out topics matching this regex (repeatable)."),
    ] = None
    node: Annotated[
        str | None, typer.Option("--node", help="The topics this node subscribes to.")
    ] = None
    types: Annotated[
        list[str] | None,
        typer.Option("--topic-types", help="Also topics of these types (globs: sensor_msgs/*)."),
    ] = None
    exclude_types: Annotated[
        list[str] | None,
        typer.Option("--exclude-topic-types", help="Never topics of these types (globs)."),
    ] = None

    def check(self, topics: list[str]) -> None:
        """Refuse a choice of nothing, or of everything and some."""
        if not (topics or self.all_ or self.node or self.types):
            hint = "-x subtracts from -a or -e" if self.exclude else None
            raise UsageError(
                "give topics to record, or -a, -e REGEX, --topic-types or --node NAME", hint=hint
            )
        if self.all_ and topics:
            raise UsageError("-a takes every topic; do not also name topics")

    def choice(self, topics: list[str]) -> dict[str, Any]:
        """The library's ``TopicChoice`` fields (``selection``), for ``topics``."""
        return {
            "topics": topics, "all": self.all_, "regex": self.regex,
            "exclude": self.exclude or [], "node": self.node, "types": self.types or [],
            "exclude_types": self.exclude_types or [],
        }  # fmt: skip


@options_record
@dataclass
class Receiving:
    """How a live recorder receives, and the disk it keeps free (bag record, bag snapshot)."""

    tcp_nodelay: Annotated[
        bool, typer.Option("--tcpnodelay", help="Ask publishers for TCP_NODELAY.")
    ] = False
    min_space: Annotated[
        str,
        typer.Option(
            "--min-space",
            "-L",
            help="Free disk to keep: 1G, 500M, 64K, 0 (off). Below it, record stops and "
            "snapshot refuses triggers.",
        ),
    ] = "100M"

    def min_space_bytes(self) -> int:
        """``-L`` in bytes."""
        from rostools.cli.units import parse_size

        return parse_size(self.min_space, "-L")


@options_record
@dataclass
class OutputFile:
    """The file a recorder writes: its name, format and chunks (bag record, bag snapshot)."""

    output_name: Annotated[
        str | None,
        typer.Option(
            "--output-name", "-O", help="The file name, .bag added (snapshot: then NAME_1, ...)."
        ),
    ] = None
    output_prefix: Annotated[
        str | None, typer.Option("--output-prefix", "-o", help="A prefix for a dated file name.")
    ] = None
    storage: Annotated[
        str | None,
        typer.Option(
            "--storage", "-s", help="File format: bag or mcap (default: from -O, else bag)."
        ),
    ] = None
    bz2: Annotated[bool, typer.Option("--bz2", "-j", help="bz2 chunks (.bag).")] = False
    lz4: Annotated[bool, typer.Option("--lz4", help="lz4 chunks (.bag or MCAP).")] = False
    compression: Annotated[
        str | None,
        typer.Option("--compression", help="none, bz2, lz4 (.bag); zstd, lz4, none (MCAP)."),
    ] = None
    chunk_size: Annotated[
        int | None, typer.Option("--chunksize", help="Chunk size in KB (default 768).")
    ] = None

    def path(self, now: float | None = None) -> tuple[Path, str]:
        """The file to write and its format, from ``-O``, ``-o`` and ``--storage``.

        As rosbag: ``-O x`` writes ``x.bag``; ``-o p`` writes ``p_<date-time>.bag``; neither
        writes ``<date-time>.bag``. A name ending in ``.mcap`` means MCAP, as ``--storage
        mcap`` does.
        """
        name, prefix = self.output_name, self.output_prefix
        if name is not None and prefix is not None:
            raise UsageError("-O and -o cannot be combined")
        given = name if name is not None else prefix
        suffix = Path(given).suffix.lower() if given else ""
        storage = self.storage or ("mcap" if suffix == ".mcap" else "bag")
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

    def folder(self, now: float | None = None) -> Path:
        """The rosbag2 folder of ``--to ros2``: ``-O NAME`` is ``NAME``, else dated as ``path``."""
        if self.output_name is not None and self.output_prefix is None:
            return Path(self.output_name)
        name = self.path(now)[0]
        return name.with_name(name.name.removesuffix(name.suffix))

    def chunk_compression(self, storage: str) -> str | None:
        """The chunk compression from ``--bz2``/``--lz4``/``--compression`` (None: default)."""
        from rostools.bag.formats.access import WRITE_COMPRESSIONS

        picked = (("bz2", self.bz2), ("lz4", self.lz4), (self.compression, self.compression))
        chosen = [c for c, on in picked if on]
        if len(set(chosen)) > 1:
            raise UsageError("give one compression: --bz2, --lz4 or --compression")
        allowed = WRITE_COMPRESSIONS[storage]
        if chosen and chosen[0] not in allowed:
            raise UsageError(f"{storage} files cannot use {chosen[0]} (use {', '.join(allowed)})")
        return chosen[0] if chosen else None

    def chunk_bytes(self) -> int | None:
        """``--chunksize`` in bytes (None: the default)."""
        return self.chunk_size * 1024 if self.chunk_size else None


@options_record
@dataclass
class Splitting:
    """When a recording stops or starts a new file (bag record)."""

    split: Annotated[
        bool, typer.Option("--split", help="Start a new file at --size or --duration.")
    ] = False
    size: Annotated[int | None, typer.Option("--size", help="Stop (or split) at this many MB.")] = (
        None
    )
    duration: Annotated[
        str | None, typer.Option("--duration", help="Stop (or split) after 30, 30s, 5m, 2h.")
    ] = None
    max_splits: Annotated[
        int | None,
        typer.Option(
            "--max-splits",
            help="Keep only the newest N closed split files, and the last (rosbag: N + 1 in all).",
        ),
    ] = None
    repeat_latched: Annotated[
        bool,
        typer.Option("--repeat-latched", help="Copy latched messages into every split file."),
    ] = False


@options_record
@dataclass
class Playback:
    """How bag play publishes: pace, time range, clock, pauses and publishers."""

    rate: Annotated[
        float, typer.Option("--rate", "-r", click_type=FINITE, help="Speed factor.")
    ] = 1.0
    start: Annotated[
        float,
        typer.Option(
            "--start", "-s", click_type=FINITE, help="Start this many seconds into the bags."
        ),
    ] = 0.0
    duration: Annotated[
        float | None,
        typer.Option("--duration", "-u", click_type=FINITE, help="Play only this many seconds."),
    ] = None
    loop_: Annotated[bool, typer.Option("--loop", "-l", help="Play again and again.")] = False
    clock: Annotated[bool, typer.Option("--clock", help="Publish bag time on /clock.")] = False
    hz: Annotated[
        float, typer.Option("--hz", click_type=FINITE, help="/clock messages per second.")
    ] = 100.0
    delay: Annotated[
        float,
        typer.Option("--delay", "-d", click_type=FINITE, help="Seconds to wait after advertising."),
    ] = 0.2
    immediate: Annotated[
        bool, typer.Option("--immediate", "-i", help="Publish everything without waiting.")
    ] = False
    pause: Annotated[bool, typer.Option("--pause", help="Start paused.")] = False
    prefix: Annotated[
        str, typer.Option("--prefix", "-p", help="Put this before every topic name.")
    ] = ""
    keep_alive: Annotated[
        bool, typer.Option("--keep-alive", "-k", help="Stay up after the end (latched topics).")
    ] = False
    skip_empty: Annotated[
        float | None,
        typer.Option("--skip-empty", click_type=FINITE, help="Skip gaps longer than this (s)."),
    ] = None
    queue: Annotated[int, typer.Option("--queue", help="Publisher queue size.")] = 100
    wait_for_subscribers: Annotated[
        bool,
        typer.Option("--wait-for-subscribers", help="Wait for a subscriber on every topic."),
    ] = False
    pause_topics: Annotated[
        list[str] | None,
        typer.Option(
            "--pause-topics", help="Pause before each message on these topics (repeat or commas)."
        ),
    ] = None
    rate_control_topic: Annotated[
        str | None,
        typer.Option(
            "--rate-control-topic",
            help="Hold playback while this topic's header stamps lag bag time.",
        ),
    ] = None
    rate_control_max_delay: Annotated[
        float,
        typer.Option(
            "--rate-control-max-delay",
            click_type=FINITE,
            help="The lag (s) allowed before holding.",
        ),
    ] = 1.0

    def options(self, topics: list[str]) -> PlayOptions:
        """The player's options for ``topics``, checked as rosbag play checks them."""
        from rostools.bag.live.player import PlayOptions

        for value, flag in ((self.delay, "-d"), (self.start, "-s")):
            if value < 0:
                raise UsageError(f"{flag} cannot be negative")
        return PlayOptions(
            rate=self.rate, start=self.start, duration=self.duration, loop=self.loop_,
            clock=self.clock, hz=self.hz, delay=self.delay, immediate=self.immediate,
            pause=self.pause, topics=topics, prefix=self.prefix, keep_alive=self.keep_alive,
            skip_empty=self.skip_empty, queue_size=self.queue,
            wait_for_subscribers=self.wait_for_subscribers,
            pause_topics=[t for item in self.pause_topics or [] for t in item.split(",") if t],
            rate_control_topic=self.rate_control_topic,
            rate_control_max_delay=self.rate_control_max_delay,
        )  # fmt: skip


@options_record
@dataclass
class CopyWindow:
    """Which messages a copying command takes: its topics and time range (filter, merge)."""

    topics: TopicsOpt = None
    start: StartOpt = None
    end: EndOpt = None

    def bounds(self, paths: list[Path]) -> tuple[int | None, int | None]:
        """``--start``/``--end`` as ns, from the earliest start among ``paths``."""
        from rostools.cli.bag.shared import time_window

        return time_window(paths, self.start, self.end)


@options_record
@dataclass
class CopyOutput:
    """How a copying command writes (filter, convert, merge, split).

    Renames, compression, overwriting, the progress bar, and whether it checks MCAP CRCs as
    it reads.
    """

    rename: RenameOpt = None
    rename_type: RenameTypeOpt = None
    compression: CompressionOpt = None
    force: ForceOpt = False
    quiet: QuietOpt = False
    no_crc_check: NoCrcCheckOpt = False

    def renames(self) -> Renames | None:
        """The rules of ``--rename`` and ``--rename-type``, or None when there are none."""
        from rostools.cli.bag.shared import renames

        return renames(self.rename, self.rename_type)

    def copy(
        self, window: CopyWindow | None = None, paths: list[Path] | None = None, **more: Any
    ) -> CopyOptions:
        """The library's ``CopyOptions``: these options, ``window``'s and ``more``'s.

        ``window``'s times count from the earliest start of ``paths``; ``more`` holds what a
        command adds (``expression``, ``chunk_size``).
        """
        from rostools.bag.tools.options import CopyOptions

        lo, hi = window.bounds(paths or []) if window else (None, None)
        return CopyOptions(
            topics=(window.topics or None) if window else None, start=lo, end=hi,
            compression=self.compression, overwrite=self.force, renames=self.renames(),
            check_crcs=not self.no_crc_check, **more,
        )  # fmt: skip


@options_record
@dataclass
class Buffering:
    """What bag snapshot keeps in memory, and what its own triggers write."""

    duration: Annotated[
        str, typer.Option("--duration", "-d", help="The time the buffer spans: 30, 30s, 5m, 2h.")
    ] = "30"
    size: Annotated[
        int, typer.Option("--size", help="Memory for the buffer, all topics together, in MB.")
    ] = 256
    topic_size: Annotated[
        int | None, typer.Option("--topic-size", help="Memory for each topic's buffer, in MB.")
    ] = None
    before: Annotated[
        str | None,
        typer.Option("--before", help="What ~trigger, SIGUSR1 and s write from the buffer."),
    ] = None
    after: Annotated[
        str | None,
        typer.Option("--after", help="...and how long they go on writing live messages."),
    ] = None
    clear_on_write: Annotated[
        bool, typer.Option("--clear-on-write", help="Empty the buffer of what a trigger takes.")
    ] = False
    max_writes: Annotated[
        int, typer.Option("--max-writes", help="Files written at once; more triggers refused.")
    ] = 4
