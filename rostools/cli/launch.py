"""Start-up: run a quick command without importing Typer, or hand over to Typer.

``quick.json`` holds the grammar Typer itself has for each command marked with
``rostools.cli.quick.runs`` (options, arguments, types, defaults), written by
``python -m rostools.cli.completion``. ``dispatch`` reads the command line with it and calls
the command's body directly. A command line it does not read exactly as Typer would (help,
an unknown option, a missing argument, a bad value, bundled short flags) is not guessed at:
Typer gets it, and runs the same body or says what is wrong. ``ROSTOOLS_NO_QUICK=1``
sends everything to Typer.
"""

from __future__ import annotations

import math
import os

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from collections.abc import Sequence
    from typing import Any

#: Not a ``pathlib.Path``: that import alone is 7 ms of start-up.
QUICK = os.path.join(os.path.dirname(__file__), "quick.json")


class _NotQuick(Exception):  # noqa: N818 - a signal, not an error
    """The command line is not one the launcher reads; Typer will."""


def dispatch(argv: Sequence[str]) -> int | None:
    """Run ``argv`` if it is a quick command line and return its status, else None."""
    if argv[:1] == ["__complete"]:  # the shells' completion scripts call this
        from rostools.cli.completer import main

        return main(list(argv[1:]))
    if os.environ.get("ROSTOOLS_NO_QUICK") or not argv:
        return None
    from rostools.names import split_remappings, use_command_namespace

    args, remappings = split_remappings(list(argv))
    use_command_namespace(remappings)
    import json  # here, not at the top: completion and an empty line never need it

    try:
        with open(QUICK, encoding="utf-8") as f:
            specs: dict[str, Any] = json.load(f)
    except OSError:  # an install without it is slower, not broken
        return None
    try:
        at, root = _globals(specs[""], args)
        spec = specs.get(" ".join(args[at : at + 2]))
        if spec is None:
            return None
        values = parse(spec, args[at + 2 :])
    except _NotQuick:
        return None
    from rostools.cli.output import Format
    from rostools.cli.settings import Settings

    settings = Settings(root["master_uri"], Format(root["fmt"]), root["debug"], remappings)
    module, _, function = spec["target"].partition(":")
    # __import__, not importlib.import_module: importlib brings warnings with it (1 ms).
    getattr(__import__(module, fromlist=[function]), function)(settings, **values)
    return 0


def _globals(spec: dict[str, Any], argv: list[str]) -> tuple[int, dict[str, Any]]:
    """The root options before the group: their values, and where the group starts."""
    values = dict(spec["defaults"])
    at = 0
    while at < len(argv) and argv[at].startswith("-"):
        at = _option(spec, argv, at, values)
    return at, values


def parse(spec: dict[str, Any], argv: list[str]) -> dict[str, Any]:
    """The parameter values of one command line, as Typer would pass them."""
    values = dict(spec["defaults"])
    positional: list[str] = []
    at = 0
    while at < len(argv):
        word = argv[at]
        if word == "--":
            positional += argv[at + 1 :]
            break
        if word.startswith("-") and word != "-":
            at = _option(spec, argv, at, values)
        else:
            positional.append(word)
            at += 1
    for arg in spec["args"]:
        if arg["many"]:
            if arg["required"] and not positional:
                raise _NotQuick  # ``node info`` alone: Typer says the argument is missing
            values[arg["dest"]], positional = [_convert(arg, v) for v in positional], []
        elif positional:
            values[arg["dest"]] = _convert(arg, positional.pop(0))
        elif arg["required"]:
            raise _NotQuick
    if positional:
        raise _NotQuick  # too many arguments: Typer says so
    return values


def _option(spec: dict[str, Any], argv: list[str], at: int, values: dict[str, Any]) -> int:
    """Read the option at ``argv[at]`` into ``values``; the index after it."""
    name, eq, inline = argv[at].partition("=") if argv[at].startswith("--") else (argv[at], "", "")
    option = spec["options"].get(name)
    if option is None or option["type"] in ("eager", "bounded"):
        raise _NotQuick  # -h, an unknown or bundled option, --version, a bounded number
    if option["flag"]:
        if eq:
            raise _NotQuick
        values[option["dest"]] = not option.get("negative", False)
        return at + 1
    if eq:
        text, at = inline, at + 1
    elif at + 1 < len(argv):
        text, at = argv[at + 1], at + 2
    else:
        raise _NotQuick
    value = _convert(option, text)
    if option["multiple"]:
        values[option["dest"]] = [*(values[option["dest"]] or []), value]
    else:
        values[option["dest"]] = value
    return at


def _convert(param: dict[str, Any], text: str) -> Any:
    """A value as Typer converts it; anything doubtful is Typer's to judge."""
    kind = param["type"]
    if kind in ("text", "str"):
        return text
    if kind == "path":
        from pathlib import Path

        return Path(text)
    if kind == "choice" and text in param["choices"]:
        return text
    if kind in ("float", "float range"):
        try:
            number = float(text)
        except ValueError:
            raise _NotQuick from None
        if math.isfinite(number):
            return number
    raise _NotQuick
