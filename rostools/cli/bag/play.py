"""``rostools bag play``: rosbag play, with its keys (space, s) and status line."""

from __future__ import annotations

import contextlib
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from rostools.bag.model import counted
from rostools.cli.bag.files import check_read
from rostools.cli.bag.group import app
from rostools.cli.bag.keys import keyboard
from rostools.cli.common import FINITE, FormatOpt, node_session, output_format
from rostools.cli.output import Format, render
from rostools.errors import UsageError, one_line

if TYPE_CHECKING:
    import asyncio

    from rostools.bag.play import Status
    from rostools.node.node import Node


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
    from rostools.bag.play import State

    tail = f"   Delay: {status.delay:.2f} " if status.state is State.DELAYED else " " * 15
    return (
        f" [{status.state.value}]  Bag Time: {status.bag_time / 1e9:13.6f}   "
        f"Duration: {status.elapsed:.6f} / {status.total:.6f}{tail}\r"
    )


@app.command()
def play(
    ctx: typer.Context,
    bags: Annotated[
        list[str] | None,
        typer.Argument(help="Bags to play, merged in time order.", show_default=False),
    ] = None,
    rate: Annotated[
        float, typer.Option("--rate", "-r", click_type=FINITE, help="Speed factor.")
    ] = 1.0,
    start: Annotated[
        float,
        typer.Option(
            "--start", "-s", click_type=FINITE, help="Start this many seconds into the bags."
        ),
    ] = 0.0,
    duration: Annotated[
        float | None,
        typer.Option("--duration", "-u", click_type=FINITE, help="Play only this many seconds."),
    ] = None,
    loop_: Annotated[bool, typer.Option("--loop", "-l", help="Play again and again.")] = False,
    clock: Annotated[bool, typer.Option("--clock", help="Publish bag time on /clock.")] = False,
    hz: Annotated[
        float, typer.Option("--hz", click_type=FINITE, help="/clock messages per second.")
    ] = 100.0,
    delay: Annotated[
        float,
        typer.Option("--delay", "-d", click_type=FINITE, help="Seconds to wait after advertising."),
    ] = 0.2,
    immediate: Annotated[
        bool, typer.Option("--immediate", "-i", help="Publish everything without waiting.")
    ] = False,
    pause: Annotated[bool, typer.Option("--pause", help="Start paused.")] = False,
    topics: Annotated[
        list[str] | None, typer.Option("--topics", help="Only these topics (repeat or commas).")
    ] = None,
    prefix: Annotated[
        str, typer.Option("--prefix", "-p", help="Put this before every topic name.")
    ] = "",
    keep_alive: Annotated[
        bool, typer.Option("--keep-alive", "-k", help="Stay up after the end (latched topics).")
    ] = False,
    skip_empty: Annotated[
        float | None,
        typer.Option("--skip-empty", click_type=FINITE, help="Skip gaps longer than this (s)."),
    ] = None,
    queue: Annotated[int, typer.Option("--queue", help="Publisher queue size.")] = 100,
    wait_for_subscribers: Annotated[
        bool,
        typer.Option("--wait-for-subscribers", help="Wait for a subscriber on every topic."),
    ] = False,
    pause_topics: Annotated[
        list[str] | None,
        typer.Option(
            "--pause-topics", help="Pause before each message on these topics (repeat or commas)."
        ),
    ] = None,
    rate_control_topic: Annotated[
        str | None,
        typer.Option(
            "--rate-control-topic",
            help="Hold playback while this topic's header stamps lag bag time.",
        ),
    ] = None,
    rate_control_max_delay: Annotated[
        float,
        typer.Option(
            "--rate-control-max-delay",
            click_type=FINITE,
            help="The lag (s) allowed before holding.",
        ),
    ] = 1.0,
    bag_list: Annotated[
        list[str] | None,
        typer.Option("--bags", help="More bags (rosbag's form after --topics /a /b)."),
    ] = None,
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="No status line.")] = False,
    fmt: FormatOpt = None,
) -> None:
    """Publish the messages of bags at their recorded pace (rosbag play).

    Remap topics with old:=new arguments. Keys: space pauses, s steps while paused, t turns
    --pause-topics on and off. The service ~pause_playback (std_srvs/SetBool) pauses too.
    """
    from rostools.bag.access import open_bag, require_ros1
    from rostools.bag.play import Player, PlayOptions

    paths, wanted = split_bags_and_topics(bags or [], topics or [])
    paths += [Path(b) for b in bag_list or []]
    if not paths:
        raise UsageError("give at least one bag to play")
    for value, flag in ((delay, "-d"), (start, "-s")):
        if value < 0:
            raise UsageError(f"{flag} cannot be negative")
    opts = PlayOptions(
        rate=rate, start=start, duration=duration, loop=loop_, clock=clock, hz=hz, delay=delay,
        immediate=immediate, pause=pause, topics=wanted, prefix=prefix, keep_alive=keep_alive,
        skip_empty=skip_empty, queue_size=queue, wait_for_subscribers=wait_for_subscribers,
        pause_topics=[t for item in pause_topics or [] for t in item.split(",") if t],
        rate_control_topic=rate_control_topic, rate_control_max_delay=rate_control_max_delay,
    )  # fmt: skip
    out = output_format(ctx, fmt)
    show_status = not quiet and out is Format.text
    terminal = sys.stderr.isatty()
    with contextlib.ExitStack() as stack:
        readers = [stack.enter_context(open_bag(p)) for p in paths]
        for reader in readers:
            require_ros1(reader, "bag play", wanted)

        async def main(node: Node, stop: asyncio.Event) -> int:
            import asyncio

            player = Player(node, readers, opts)
            if show_status:
                player.measure_topics()
                for path in paths:
                    sys.stderr.write(f"Opening {one_line(path)}\n")
            keys = {" ": player.toggle_pause, "s": player.step, "t": player.toggle_pause_topics}
            with keyboard(keys, asyncio.get_running_loop()) as keys_read:
                if show_status and keys_read:
                    sys.stderr.write("Hit space to toggle paused, or 's' to step.\n")
                    if opts.pause_topics:
                        sys.stderr.write("Hit 't' to toggle pausing on --pause-topics.\n")
                if not show_status:
                    return await player.run(stop)
                return await player.run(stop, StatusLines(terminal), _say)

        sent = node_session(ctx, main, "rostools_play")
    if show_status:
        sys.stderr.write("\nDone.\n" if terminal else "Done.\n")
    elif out is not Format.text:
        sys.stdout.write(render(out, {"published": sent}) + "\n")
    check_read(readers, f"published {counted(sent, 'message')}")


def _say(text: str) -> None:
    sys.stderr.write(text)
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

        from rostools.bag.play import State

        if self.terminal:
            sys.stderr.write(status_line(status))
        else:
            now = time.monotonic()
            if now < self.due and status.state is not State.DONE:
                return
            self.due = now + self.PERIOD
            sys.stderr.write(status_line(status).rstrip("\r").rstrip() + "\n")
        sys.stderr.flush()
