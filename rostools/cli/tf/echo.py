"""``rostools tf echo``: one transform, as tf_echo prints it (live or from a bag).

``tf echo A B`` prints B's pose in A: the transform that takes data in B to A, tf2's
``lookupTransform(A, B, time)``, as ``tf_echo A B`` does.
"""

from __future__ import annotations

import math
import sys
import time
from decimal import Decimal, InvalidOperation
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rostools.cli import output
from rostools.cli.common import FINITE, FormatOpt, NoCrcCheckOpt, node_session, output_format
from rostools.cli.declare import command
from rostools.cli.output import Format
from rostools.cli.tf.options import BagOpt, CountOpt, FrameArg, TimeoutOpt
from rostools.errors import NotFoundError, TimeoutExpired, UsageError, one_line

if TYPE_CHECKING:
    import asyncio
    from pathlib import Path

    from rostools.node.node import LiveNode
    from rostools.tf.buffer import TransformBuffer
    from rostools.tf.records import Stamped

#: With ``--at`` in a bag, the buffer keeps the whole recording: the longest cache tf2's
#: ``ros::Duration`` can say (2^31 - 1 s), so no stamp of a real recording is pruned.
WHOLE_RECORDING_NS = (2**31 - 1) * 1_000_000_000

RateOpt = Annotated[
    float,
    typer.Option(
        "--rate", "-r", click_type=FINITE, help="Lookups a second (of the bag's time with -b)."
    ),
]
AtOpt = Annotated[
    list[str] | None,
    typer.Option(
        "--at",
        help="Look up at this time (s): absolute (ROS time), or +T/-T relative: to the bag's"
        " start with -b, to now live. Default: the latest common time. With -b, repeat it"
        " for several times (one answer each).",
        show_default=False,
    ),
]


@command()
def echo(
    ctx: typer.Context,
    source: FrameArg,
    target: FrameArg,
    rate: RateOpt = 1.0,
    at: AtOpt = None,
    bag: BagOpt = None,
    verbose: Annotated[bool, typer.Option("--verbose", "-v", help="Print the 4x4 matrix.")] = False,
    precision: Annotated[
        int, typer.Option("--precision", "-p", min=0, max=17, help="Decimals printed.")
    ] = 3,
    count: CountOpt = None,
    timeout: TimeoutOpt = None,
    cache_time: Annotated[
        float,
        typer.Option("--cache-time", click_type=FINITE, help="Seconds of transforms kept (tf2's)."),
    ] = 10.0,
    no_crc_check: NoCrcCheckOpt = False,
    fmt: FormatOpt = None,
) -> None:
    """Print TARGET's pose in SOURCE, the transform from TARGET to SOURCE (tf_echo)."""
    fmt = output_format(ctx, fmt)
    frames = _frame(source), _frame(target)
    if not rate > 0:
        raise UsageError(f"--rate must be above 0, not {rate:g}")
    if count is not None and count < 1:
        raise UsageError("-n must be 1 or more")
    if not cache_time > 0:
        raise UsageError(f"--cache-time must be above 0, not {cache_time:g}")
    cache_ns = round(cache_time * 1e9)
    times = [_parse_at(a) for a in at or []]
    if len(times) > 1 and bag is None:
        raise UsageError("several --at need --bag (live, one time is looked up at each tick)")
    when = times[0] if times else None
    show = _printer(fmt, verbose, precision)
    if bag is not None:
        if timeout is not None:
            raise UsageError("--timeout does not apply to a bag (-b): it is read to its end")
        _from_bag(bag, frames, times, rate, count, cache_ns, show, not no_crc_check)
        return
    if no_crc_check:
        raise UsageError("--no-crc-check needs --bag")
    result = node_session(
        ctx,
        lambda node, stop: _live(node, stop, frames, when, rate, count, cache_ns, timeout, show),
        "rostools_tf_echo",
        fmt,
    )
    if isinstance(result, Exception):
        raise result


def _frame(name: str) -> str:
    """A frame id as tf_echo takes it: one leading ``/`` dropped (tf1's ``strip_leading_slash``)."""
    frame = name[1:] if name.startswith("/") else name
    if not frame:
        raise UsageError("a frame id cannot be empty")
    return frame


def _parse_at(text: str) -> tuple[bool, int]:
    """``--at``: (relative, ns). ``+T``/``-T`` is relative; decimals are read exactly."""
    relative = text[:1] in ("+", "-")
    try:
        value = Decimal(text.strip())
    except InvalidOperation:
        raise UsageError(f"--at takes seconds (1700000000.5, +2.5 or -1), not {text!r}") from None
    if not value.is_finite() or (not relative and value < 0):
        raise UsageError(f"--at takes seconds (1700000000.5, +2.5 or -1), not {text!r}")
    return relative, int(value * 1_000_000_000)


def _printer(fmt: Format, verbose: bool, precision: int) -> Any:
    """What prints one answer, in ``fmt``."""

    def show(t: Stamped) -> None:
        output.write(fmt, _record(t), lambda r: _text(r, verbose, precision))

    return show


def _record(t: Stamped) -> dict[str, Any]:
    """One answer as data: tf2's names, the RPY and the matrix."""
    from rostools.tf import scalar

    angles = list(scalar.rpy(t.rotation))
    rows = [[*row, v] for row, v in zip(scalar.matrix(t.rotation), t.translation, strict=True)]
    return {
        "time": t.stamp_ns / 1e9,
        "stamp_ns": t.stamp_ns,
        "frame_id": t.parent,
        "child_frame_id": t.child,
        "translation": list(t.translation),
        "rotation": list(t.rotation),
        "rpy": angles,
        "rpy_degrees": [math.degrees(v) for v in angles],
        "matrix": [*rows, [0.0, 0.0, 0.0, 1.0]],
    }


def _text(r: dict[str, Any], verbose: bool, p: int) -> str:
    """tf_echo's layout, with ``p`` decimals (tf_echo's own: 3)."""

    def row(values: list[float]) -> str:
        return ", ".join(f"{v:.{p}f}" for v in values)

    lines = [
        f"At time {r['time']:.{p}f}",
        f"- Translation: [{row(r['translation'])}]",
        f"- Rotation: in Quaternion [{row(r['rotation'])}]",
        f"            in RPY (radian) [{row(r['rpy'])}]",
        f"            in RPY (degree) [{row(r['rpy_degrees'])}]",
    ]
    if verbose:
        width = p + 4
        lines.append("- Matrix:")
        lines += ["  " + " ".join(f"{v:{width}.{p}f}" for v in m) for m in r["matrix"]]
    return "\n".join(lines)


def _lookup(buffer: TransformBuffer, frames: tuple[str, str], at_ns: int) -> Stamped:
    return buffer.lookup(frames[0], frames[1], at_ns)


def _warn(err: Exception) -> None:
    sys.stderr.write(f"rostools: {one_line(str(err))}\n")
    sys.stderr.flush()


def _from_bag(
    path: Path,
    frames: tuple[str, str],
    times: list[tuple[bool, int]],
    rate: float,
    count: int | None,
    cache_ns: int,
    show: Any,
    check_crcs: bool,
) -> None:
    """Print from a bag: with ``--at``, a lookup at each time over the whole recording.

    Otherwise step through it at ``rate`` (of the bag's record time): at each step, what a
    listener would print at that moment of a play.
    """
    from rostools.cli.tf.shared import open_feed
    from rostools.tf.buffer import TransformBuffer, TransformError

    with open_feed(path, check_crcs) as feed:
        start = feed.start_ns or 0
        if times:
            if count is not None:
                raise UsageError("-n does not apply to lookups at given times (--at)")
            whole = TransformBuffer(max(cache_ns, WHOLE_RECORDING_NS))
            for batch in feed.batches():
                whole.set_transforms(batch.transforms, batch.broadcaster, batch.static)
            for relative, ns in times:
                try:
                    show(_lookup(whole, frames, start + ns if relative else ns))
                except TransformError as err:
                    if not relative and 0 < ns < start:  # meant from the start, likely
                        err.hint = f"--at +{ns / 1e9:g} counts from the recording's start"
                    raise
            return
        buffer = TransformBuffer(cache_ns)
        period = max(1, round(1e9 / rate))
        tick, printed = start, 0
        last: Exception | None = None

        def step() -> bool:
            """One lookup at ``tick``; False once ``count`` are printed."""
            nonlocal printed, last
            try:
                answer = _lookup(buffer, frames, 0)
            except (TransformError, NotFoundError) as err:
                last = err
                if printed:  # before the first answer, tf_echo waits quietly
                    _warn(err)
                return True
            show(answer)
            printed += 1
            return count is None or printed < count

        for batch in feed.batches():
            while batch.received_ns > tick:
                if not step():
                    return
                tick += period
            buffer.set_transforms(batch.transforms, batch.broadcaster, batch.static)
        end = feed.end_ns if feed.end_ns is not None else tick
        while tick <= end:
            if not step():
                return
            tick += period
        if not printed and last is not None:
            raise last


async def _live(
    node: LiveNode,
    stop: asyncio.Event,
    frames: tuple[str, str],
    when: tuple[bool, int] | None,
    rate: float,
    count: int | None,
    cache_ns: int,
    timeout: float | None,
    show: Any,
) -> Exception | None:
    """Listen; wait (up to ``timeout``) for the first answer, then print one per ``1/rate`` s.

    Returns the error to end with (a timeout), or None.
    """
    import asyncio
    import contextlib

    from rostools.cli.tf.shared import LiveFeed
    from rostools.tf.buffer import TransformBuffer, TransformError

    buffer = TransformBuffer(cache_ns)
    arrived = asyncio.Event()

    def on_batch(batch: Any) -> None:
        buffer.set_transforms(batch.transforms, batch.broadcaster, batch.static)
        arrived.set()

    def at_ns() -> int:
        if when is None:
            return 0
        relative, ns = when
        return time.time_ns() + ns if relative else ns

    loop = asyncio.get_running_loop()
    deadline = loop.time() + timeout if timeout is not None else None
    feed = LiveFeed(node, on_batch)
    await feed.start()
    printed = 0
    last: Exception | None = None
    try:
        while not stop.is_set():  # the first answer, as soon as the data allows it
            try:
                show(_lookup(buffer, frames, at_ns()))
                printed = 1
                break
            except (TransformError, NotFoundError) as err:
                last = err
            left = None if deadline is None else deadline - loop.time()
            if left is not None and left <= 0:
                return TimeoutExpired(
                    f"no transform from {frames[1]} to {frames[0]} within {timeout:g} s: {last}"
                )
            arrived.clear()
            waits = [asyncio.ensure_future(arrived.wait()), asyncio.ensure_future(stop.wait())]
            # a time-relative lookup may succeed with no new data: look again each 0.1 s
            pause = 0.1 if left is None else min(left, 0.1)
            await asyncio.wait(waits, timeout=pause, return_when="FIRST_COMPLETED")
            for w in waits:
                w.cancel()
        period = 1.0 / rate
        tick = loop.time() + period
        while not stop.is_set() and (count is None or printed < count):
            with contextlib.suppress(asyncio.TimeoutError):
                await asyncio.wait_for(stop.wait(), max(tick - loop.time(), 0))
            if stop.is_set():
                break
            tick += period
            try:
                show(_lookup(buffer, frames, at_ns()))
                printed += 1
            except (TransformError, NotFoundError) as err:
                _warn(err)
    finally:
        await feed.close()
    return None
