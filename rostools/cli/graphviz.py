"""Graphviz for the commands that draw (``node graph``, ``tf frames``): DOT names, ``-o``.

Quoted DOT names and labels, and ``-o`` drawn through Graphviz's ``dot``.

``-o x.svg`` (or .png, .pdf) draws the DOT through ``dot``; ``.dot`` and ``.gv`` are written as
DOT. Without ``dot`` on PATH the DOT is written beside the name asked for (``x.dot``) and the
command says so in one line, exit 3 (not found), so a script knows the picture is missing and a
person has the graph to render elsewhere.
"""

from __future__ import annotations

import enum
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Final

import typer

from rostools.cli import output
from rostools.cli.common import settings
from rostools.cli.output import Format, check_writable, emit
from rostools.errors import (
    NotFoundError,
    RostoolsError,
    TimeoutExpired,
    UsageError,
    cannot_write,
    one_line,
)

#: Pictures ``-o`` asks ``dot`` for, by file suffix; ``.dot`` and ``.gv`` are written as DOT.
DOT_FORMATS: Final = ("svg", "png", "pdf")
DOT_SUFFIXES: Final = (".dot", ".gv")
#: Seconds ``dot`` may take to lay out the graph.
DOT_TIMEOUT: Final = 60.0


class GraphFormat(str, enum.Enum):
    """Output formats of a command that draws a graph: the usual ones and Graphviz."""

    text = "text"
    json = "json"
    yaml = "yaml"
    dot = "dot"


#: ``--format`` of a command that draws: the usual formats, and the DOT itself.
GraphFormatOpt = Annotated[
    GraphFormat | None,
    typer.Option(
        "--format", "-F", help="text (a tree), json, yaml or dot (Graphviz).", show_default=False
    ),
]
#: ``-o`` of a command that draws: a picture through Graphviz, or the DOT.
PictureOpt = Annotated[
    Path | None,
    typer.Option(
        "--output",
        "-o",
        help="Draw into a file through Graphviz's dot: .svg, .png, .pdf (.dot, .gv: the DOT).",
        show_default=False,
    ),
]


def show_graph(
    ctx: typer.Context,
    fmt: GraphFormat | None,
    out: Path | None,
    dot: Callable[[], str],
    text: Callable[[], str | None],
    data: Callable[[], object],
) -> None:
    """Draw into ``out``, or print the graph as ``fmt`` (or the run's format) asks.

    ``text`` gives None when it has said why there is nothing to show.
    """
    if out is not None:
        draw(dot() + "\n", out)
        return
    chosen = fmt if fmt is not None else GraphFormat(settings(ctx).format.value)
    if chosen is GraphFormat.dot:
        output.put(dot() + "\n")
    elif chosen is GraphFormat.text:
        shown = text()
        if shown is not None:
            output.put(shown + "\n")
    else:
        emit(Format(chosen.value), data())


def dot_id(text: str) -> str:
    r"""A quoted DOT ID on one line, distinct for distinct names.

    Backslashes are doubled before control characters become escapes (``\n``), so that a
    name holding a backslash and an ``n`` and one holding a newline stay two nodes.
    """
    return '"' + one_line(text.replace("\\", "\\\\")).replace('"', '\\"') + '"'


def dot_label(*parts: str) -> str:
    r"""A quoted DOT label: ``parts`` on lines of their own, each shown as ``one_line`` shows it.

    Graphviz reads ``\n`` in a label as a line break and ``\\`` as a backslash, so the
    escapes are written with their backslash doubled: they are shown, not obeyed.
    """
    shown = (one_line(p).replace("\\", "\\\\").replace('"', '\\"') for p in parts)
    return '"' + "\\n".join(shown) + '"'


def picture_kind(path: Path) -> str | None:
    """The format ``dot`` is asked for (None: write the DOT itself)."""
    suffix = path.suffix.lower()
    if suffix in DOT_SUFFIXES:
        return None
    if suffix.lstrip(".") not in DOT_FORMATS:
        raise UsageError(
            f"-o {path}: cannot tell the format from the name",
            hint="end it in " + ", ".join(["." + k for k in DOT_FORMATS] + list(DOT_SUFFIXES)),
        )
    return suffix.lstrip(".")


def draw(dot: str, path: Path) -> None:
    """Write ``dot`` to ``path`` as the picture its suffix names, through Graphviz's ``dot``.

    Without ``dot``, the DOT goes to ``path`` with a ``.dot`` suffix and ``NotFoundError``
    says where.
    """
    import shutil
    import subprocess

    kind = picture_kind(path)
    check_writable(path)
    program = shutil.which("dot") if kind is not None else None
    if kind is None or program is None:
        target = path if kind is None else path.with_suffix(".dot")
        try:
            target.write_text(dot)
        except OSError as err:
            raise cannot_write(target, err.strerror or str(err)) from err
        if kind is None:
            return
        raise NotFoundError(
            f"Graphviz's dot is not on PATH, so {path} was not drawn; the graph is in {target}",
            hint=f"install Graphviz (apt install graphviz), or: dot -T{kind} {target} -o {path}",
        )
    try:
        done = subprocess.run(
            [program, f"-T{kind}", "-o", str(path)],
            input=dot.encode(),
            capture_output=True,
            timeout=DOT_TIMEOUT,
            check=False,
        )
    except subprocess.TimeoutExpired as err:
        raise TimeoutExpired(f"dot did not lay out the graph within {DOT_TIMEOUT:g} s") from err
    if done.returncode != 0:
        why = done.stderr.decode(errors="replace").strip().splitlines()
        raise RostoolsError(f"dot could not draw {path}: {why[0] if why else done.returncode}")
