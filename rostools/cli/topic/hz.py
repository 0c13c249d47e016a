"""``rostools topic hz``: the publishing rate of topics, counting raw frames (rostopic hz)."""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Annotated

import typer

from rostools.cli import output
from rostools.cli.common import FormatOpt, output_format
from rostools.cli.declare import command
from rostools.cli.output import Format
from rostools.cli.topic.live import FilterOpt, StrictOpt, TimeoutOpt
from rostools.cli.topic.meters import COALESCE, HzWindowOpt, Meter, NodelayOpt, run_meter
from rostools.names import script_resolve

if TYPE_CHECKING:
    from rostools.msgs.codec import DecodeError
    from rostools.node.connection import Frame, InboundConnection


@command()
def hz(
    ctx: typer.Context,
    topics: Annotated[list[str], typer.Argument(help="One or more topics.")],
    window: HzWindowOpt = None,
    filter_expr: FilterOpt = None,
    wall_time: Annotated[
        bool,
        typer.Option(
            "--wall-time", help="Time arrivals by the wall clock, even under /use_sim_time."
        ),
    ] = False,
    tcp_nodelay: NodelayOpt = False,
    timeout: TimeoutOpt = None,
    strict: StrictOpt = False,
    fmt: FormatOpt = None,
) -> None:
    """The publishing rate of topics (rostopic hz); counts raw frames, decodes only for --filter."""
    from rostools.rates import DEFAULT_SPAN, DEFAULT_WINDOW, RateMeter, format_rate, rate_table

    fmt = output_format(ctx, fmt)
    names = [script_resolve(t, "rostopic") for t in topics]
    span = 0.0 if window else DEFAULT_SPAN  # an explicit window is rostopic's, exactly
    meters = {n: RateMeter(window or DEFAULT_WINDOW, span) for n in names}
    runner = Meter(names, timeout, fmt, tcp_nodelay, wall_time, COALESCE, strict)
    check = _filter(filter_expr, runner.skip)

    def sink(topic: str, frames: list[Frame], conn: InboundConnection, now: float) -> None:
        if check is not None:
            frames = check(frames, conn, topic)
        meters[topic].add(len(frames), now)

    def report(last: bool = False) -> None:
        rows = [(n, s) for n in names if (s := meters[n].report(last)) is not None]
        if fmt is not Format.text:
            for n, s in rows:
                row = {"topic": n, "rate": s.value, "min": s.min, "max": s.max,
                       "std_dev": s.std_dev, "window": s.window}  # fmt: skip
                output.write(fmt, row)
        elif not rows:
            output.put("no new messages\n")
        elif len(names) == 1:
            output.put(format_rate(rows[0][1]) + "\n")
        else:
            output.put(rate_table(rows))

    run_meter(ctx, runner, sink, report)


def _filter(
    expr: str | None, skip: Callable[[DecodeError, InboundConnection, Frame], None]
) -> Callable[[list[Frame], InboundConnection, str], list[Frame]] | None:
    """A frames filter that decodes and evaluates ``expr``, or None.

    A message that does not decode goes to ``skip`` and is not counted.
    """
    if not expr:
        return None
    from rostools.msgs import learnt
    from rostools.msgs.codec import DECODE_ERRORS, DecodeError, why_not
    from rostools.msgs.expr import compile_expression
    from rostools.msgs.store import TypeStore

    wanted = compile_expression(expr)
    base = TypeStore.default()

    def keep(frames: list[Frame], conn: InboundConnection, topic: str) -> list[Frame]:
        header = conn.header or {}
        kind, md5 = header.get("type", ""), header.get("md5sum", "")
        decode = learnt.decoder(base, kind, md5, header.get("message_definition", ""))
        kept = []
        for data in frames:
            try:
                msg = decode(data, 0)[0]
            except (DecodeError, *DECODE_ERRORS) as err:
                why = f"a message on {topic} does not decode as {kind}: {why_not(err)}"
                skip(DecodeError(why), conn, data)
                continue
            if wanted(topic, msg):
                kept.append(data)
        return kept

    return keep
