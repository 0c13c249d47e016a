"""``rostools bag play``: rosbag play, with its keys (space, s) and status line."""

from __future__ import annotations

import contextlib
import sys
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from rostools.bag.formats.model import counted
from rostools.cli import output
from rostools.cli.bag.keys import keyboard
from rostools.cli.bag.options import Playback
from rostools.cli.bag.shared import check_read
from rostools.cli.common import FormatOpt, NoCrcCheckOpt, node_session, output_format
from rostools.cli.declare import command
from rostools.cli.output import Format, render
from rostools.errors import UsageError, one_line

if TYPE_CHECKING:
    import asyncio

    from rostools.bag.formats.base import BagReader
    from rostools.bag.live.player import PlayOptions, Status
    from rostools.node.node import LiveNode


def split_bags_and_topics(args: list[str], topics: list[str]) -> tuple[list[Path], list[str]]:
    """Bags and topics from the positional arguments.

    ``rosbag play x.bag --topics /a /b`` leaves ``/b`` among the positionals; with ``--topics``
    given, a positional that is not a file but looks like a topic is taken as one more topic.
    """
    bags: list[Path] = []
    extra: list[str] = []
    for arg in args:
        if topics and arg.startswith("/") and not Path(arg).is_file():
            extra.append(arg)
        else:
            bags.append(Path(arg))
    return bags, [t for item in [*topics, *extra] for t in item.split(",") if t]


def status_line(status: Status) -> str:
    """rosbag play's status line: `` [RUNNING]  Bag Time: ...   Duration: ... / ...``."""
    from rostools.bag.live.player import State

    tail = f"   Delay: {status.delay:.2f} " if status.state is State.DELAYED else " " * 15
    return (
        f" [{status.state.value}]  Bag Time: {status.bag_time / 1e9:13.6f}   "
        f"Duration: {status.elapsed:.6f} / {status.total:.6f}{tail}\r"
    )


@command()
def play(
    ctx: typer.Context,
    bags: Annotated[
        list[str] | None,
        typer.Argument(help="Bags to play, merged in time order.", show_default=False),
    ] = None,
    playback: Playback = Playback(),  # noqa: B008 - a record of options, never changed
    topics: Annotated[
        list[str] | None, typer.Option("--topics", help="Only these topics (repeat or commas).")
    ] = None,
    bag_list: Annotated[
        list[str] | None,
        typer.Option("--bags", help="More bags (rosbag's form after --topics /a /b)."),
    ] = None,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="No status line.")] = False,
    no_crc_check: NoCrcCheckOpt = False,
    fmt: FormatOpt = None,
) -> None:
    """Publish the messages of bags at their recorded pace (rosbag play).

    Remap topics with old:=new arguments. Keys: space pauses, s steps while paused, t turns
    --pause-topics on and off. The service ~pause_playback (std_srvs/SetBool) pauses too.
    """
    from rostools.bag.formats.access import open_bag, require_ros1

    paths, wanted = split_bags_and_topics(bags or [], topics or [])
    paths += [Path(b) for b in bag_list or []]
    if not paths:
        raise UsageError("give at least one bag to play")
    opts = playback.options(wanted)
    out = output_format(ctx, fmt)
    show_status = not quiet and out is Format.text
    with contextlib.ExitStack() as stack:
        readers = [stack.enter_context(open_bag(p, check_crcs=not no_crc_check)) for p in paths]
        for reader in readers:
            require_ros1(reader, "bag play", wanted)
        run = partial(_play, readers, opts, paths if show_status else None)
        sent = node_session(ctx, run, "rostools_play")
    if show_status:
        sys.stderr.write("\nDone.\n" if sys.stderr.isatty() else "Done.\n")
    elif out is not Format.text:
        output.put(render(out, {"published": sent}) + "\n")
    check_read(readers, f"published {counted(sent, 'message')}")


async def _play(
    readers: list[BagReader],
    opts: PlayOptions,
    shown: list[Path] | None,
    node: LiveNode,
    stop: asyncio.Event,
) -> int:
    """Play ``readers`` on ``node``; with the status line and key hints when ``shown``."""
    import asyncio

    from rostools.bag.live.player import Player

    player = Player(node, readers, opts)
    if shown is not None:
        player.measure()
        for path in shown:
            sys.stderr.write(f"Opening {one_line(path)}\n")
    keys = {" ": player.toggle_pause, "s": player.step, "t": player.toggle_pause_topics}
    with keyboard(keys, asyncio.get_running_loop()) as keys_read:
        if shown is None:
            return await player.run(stop)
        hints = ["Hit space to toggle paused, or 's' to step.\n"] if keys_read else []
        if keys_read and opts.pause_topics:
            hints.append("Hit 't' to toggle pausing on --pause-topics.\n")
        return await player.run(stop, StatusLines(sys.stderr.isatty()), partial(_say, hints))


def _say(hints: list[str], text: str) -> None:
    """rosbag play's lines; the key hints after the wait's, as rosbag prints them."""
    sys.stderr.write(text)
    if text.startswith("Waiting ") and text.endswith(" done.\n"):
        sys.stderr.write("".join(hints))
    sys.stderr.flush()


class StatusLines:
    """The status line on stderr: redrawn in place on a terminal, else one line a second.

    On a terminal it is redrawn each time the player calls (every 0.1 s). Elsewhere one line
    a second ends in a newline, and so does the last: rosbag play writes its line, ended by a
    carriage return, for every message, even into a pipe.
    """

    PERIOD = 1.0  # s between lines off a terminal

    def __init__(self, terminal: bool) -> None:
        self.terminal = terminal
        self.due = 0.0  # monotonic time of the next line off a terminal

    def __call__(self, status: Status) -> None:
        """Show ``status``."""
        import time

        from rostools.bag.live.player import State

        if self.terminal:
            sys.stderr.write(status_line(status))
        else:
            now = time.monotonic()
            if now < self.due and status.state is not State.DONE:
                return
            self.due = now + self.PERIOD
            sys.stderr.write(status_line(status).rstrip("\r").rstrip() + "\n")
        sys.stderr.flush()
