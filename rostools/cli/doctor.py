"""``rostools doctor``: a roswtf for the network, one verdict a line."""

from __future__ import annotations

from typing import Annotated

import typer

from rostools.cli import output
from rostools.cli.common import FiniteFloat, FormatOpt, output_format, settings
from rostools.cli.output import Format, emit
from rostools.errors import RostoolsError, TimeoutExpired, UnreachableError, UsageError, one_line

app = typer.Typer(
    name="doctor", help="Check this host's view of the ROS graph.", add_completion=False
)

#: A failed check's exit code -> the error that carries it.
_ERRORS: dict[int, type[RostoolsError]] = {
    2: UsageError,
    4: UnreachableError,
    5: TimeoutExpired,
}


@app.command()
def doctor(
    ctx: typer.Context,
    timeout: Annotated[
        float,
        typer.Option(
            "--timeout",
            "-t",
            click_type=FiniteFloat(min=0.001),
            help="Seconds to wait for each peer.",
        ),
    ] = 2.0,
    fmt: FormatOpt = None,
) -> None:
    """Check the master, this host's name, every node, sim time and clocks (roswtf's network part).

    Exit 0 when every check passes; else the exit code of the first that failed (4: the
    master or a node cannot be reached, 5: the master did not answer in time, 2: a bad
    ROS_IP/ROS_HOSTNAME, 1: anything else).
    """
    from rostools.rosgraph.hostcheck import Doctor

    fmt = output_format(ctx, fmt)
    checks = Doctor(settings(ctx).resolved_master_uri(), timeout).run()
    failed = [c for c in checks if c.status == "fail"]
    if fmt is Format.text:
        for check in checks:
            hint = f" (hint: {check.hint})" if check.hint else ""
            verdict = one_line(check.verdict + hint)  # it names nodes and URIs from the master
            output.put(f"{check.status.upper():5} {check.name:10} {verdict}\n")
    else:
        emit(fmt, {"ok": not failed, "checks": [c.as_dict() for c in checks]})
    output.flush()
    if failed:
        names = ", ".join(c.name for c in failed)
        error = _ERRORS.get(failed[0].exit_code, RostoolsError)
        raise error(f"doctor: {len(failed)} of {len(checks)} checks failed ({names})")
