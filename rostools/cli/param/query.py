"""``rostools param list|get``: read the parameter server.

Typer-free (``rostools.cli.declare``): the launcher runs these without Typer.
"""

from __future__ import annotations

from rostools.cli import output
from rostools.cli.declare import command
from rostools.cli.output import Format, emit, lines
from rostools.cli.param.shared import TOOL, say
from rostools.names import make_global_ns, script_resolve

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from typing import Annotated

    import typer

    from rostools.cli.common import FormatOpt
    from rostools.cli.param.options import NameArg, VerboseOpt
    from rostools.cli.settings import Settings


@command("list", quick=True)
def list_params(
    s: Settings,
    namespace: Annotated[str, typer.Argument(help="Only names under this namespace.")] = "/",
    fmt: FormatOpt = None,
) -> None:
    """List parameter names, sorted."""
    ns = make_global_ns(script_resolve(namespace, TOOL))
    names = sorted(n for n in s.master(TOOL).param_names() if n.startswith(ns))
    emit(s.output_format(fmt), names, lines)


@command(quick=True)
def get(
    s: Settings,
    name: NameArg,
    pretty: Annotated[
        bool,
        typer.Option(
            "-p",
            "--pretty",
            help="As rosparam -p: text as it is, multi-line text in mappings as blocks.",
        ),
    ] = False,
    verbose: VerboseOpt = False,
    fmt: FormatOpt = None,
) -> None:
    """Print a parameter, or a whole namespace, as YAML."""
    key = script_resolve(name, TOOL)
    say(verbose, f"getting parameter [{key}]")
    value = s.master(TOOL).get_param(key)
    out = s.output_format(fmt)
    if out is Format.text:
        from rostools.cli.param import plainyaml  # PyYAML only for what it cannot print itself

        if pretty and isinstance(value, str):
            output.put(value + "\n")  # rosparam -p prints text as it is
            return
        # rosparam ends a YAML dump with a blank line, but not its -p print of a mapping
        end = "" if pretty and isinstance(value, dict) else "\n"
        output.put(plainyaml.dump(value, pretty=pretty) + end)
    else:
        from rostools.cli.param import paramyaml

        emit(out, paramyaml.to_plain(value))
