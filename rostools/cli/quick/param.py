"""``param get|list`` without Typer (see ``rostools.cli.quick``)."""

from __future__ import annotations

import sys

from rostools.cli.output import Format, emit, lines
from rostools.names import make_global_ns, script_resolve

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from rostools.cli.settings import Settings


def say(verbose: bool, text: str) -> None:
    """rosparam's -v: a line on stdout, as rosparam prints it."""
    if verbose:
        sys.stdout.write(text + "\n")


def list_params(s: Settings, namespace: str, fmt: Format | str | None) -> None:
    """List parameter names, sorted."""
    ns = make_global_ns(script_resolve(namespace, "rosparam"))
    names = sorted(n for n in s.master("rosparam").param_names() if n.startswith(ns))
    emit(s.output_format(fmt), names, lines)


def get(s: Settings, name: str, pretty: bool, verbose: bool, fmt: Format | str | None) -> None:
    """Print a parameter, or a whole namespace, as YAML."""
    key = script_resolve(name, "rosparam")
    say(verbose, f"getting parameter [{key}]")
    value = s.master("rosparam").get_param(key)
    out = s.output_format(fmt)
    if out is Format.text:
        from rostools.cli import paramdump  # PyYAML only for values it cannot print itself

        if pretty and isinstance(value, str):
            sys.stdout.write(value + "\n")  # rosparam -p prints text as it is
            return
        # rosparam ends a YAML dump with a blank line, but not its -p print of a mapping
        end = "" if pretty and isinstance(value, dict) else "\n"
        sys.stdout.write(paramdump.dump(value, pretty=pretty) + end)
    else:
        from rostools.cli import paramyaml

        emit(out, paramyaml.to_plain(value))
