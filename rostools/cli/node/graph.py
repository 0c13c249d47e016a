"""``rostools node graph``: the graph as a tree of nodes and topics, as Graphviz, or a picture.

``-o graph.svg`` (or .png, .pdf) draws the DOT through Graphviz's ``dot``, rqt_graph's
picture without a GUI. Without ``dot`` on PATH the DOT is written beside the name asked for
(``graph.dot``) and the command says so in one line, exit 3 (not found), so a script knows
the picture is missing and a person has the graph to render elsewhere.
"""

from __future__ import annotations

import enum
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Final

import typer

from rostools.cli import output
from rostools.cli.common import master, settings
from rostools.cli.declare import command
from rostools.cli.output import Format, check_writable, emit
from rostools.errors import (
    NotFoundError,
    RostoolsError,
    TimeoutExpired,
    UsageError,
    cannot_write,
    one_line,
)

if TYPE_CHECKING:
    from rostools.rosgraph.state import RosGraph


from rostools.cli.node.shared import TOOL, warn

#: Pictures ``-o`` asks ``dot`` for, by file suffix; ``.dot`` and ``.gv`` are written as DOT.
DOT_FORMATS: Final = ("svg", "png", "pdf")
DOT_SUFFIXES: Final = (".dot", ".gv")
#: Seconds ``dot`` may take to lay out the graph.
DOT_TIMEOUT: Final = 60.0


class GraphFormat(str, enum.Enum):
    """Output formats of ``node graph``: the usual ones and Graphviz."""

    text = "text"
    json = "json"
    yaml = "yaml"
    dot = "dot"


def graph_text(graph: RosGraph) -> str:
    """Each node, the topics it publishes and subscribes, and the nodes at the other end."""
    lines: list[str] = []
    for node in graph.nodes:
        lines.append(one_line(node.name))
        groups = [
            ("publishes", "→", [(t, graph.topic(t).subscribers) for t in node.publishes]),
            ("subscribes", "←", [(t, graph.topic(t).publishers) for t in node.subscribes]),
        ]
        groups = [g for g in groups if g[2]]
        if not groups:
            lines.append("└── (no topics)")
        for gi, (title, arrow, topics) in enumerate(groups):
            last_group = gi == len(groups) - 1
            lines.append(("└── " if last_group else "├── ") + title)
            stem = "    " if last_group else "│   "
            for ti, (topic, peers) in enumerate(topics):
                branch = "└── " if ti == len(topics) - 1 else "├── "
                others = (
                    ", ".join(map(one_line, peers))
                    if peers
                    else ("(no subscribers)" if arrow == "→" else "(no publishers)")
                )
                ty = graph.topic(topic).type
                lines.append(f"{stem}{branch}{one_line(topic)} [{one_line(ty)}] {arrow} {others}")
    return "\n".join(lines)


def _dot_id(text: str) -> str:
    r"""A quoted DOT ID on one line, distinct for distinct names.

    Backslashes are doubled before control characters become escapes (``\n``), so that a
    name holding a backslash and an ``n`` and one holding a newline stay two nodes.
    """
    return '"' + one_line(text.replace("\\", "\\\\")).replace('"', '\\"') + '"'


def _dot_label(*parts: str) -> str:
    r"""A quoted DOT label: ``parts`` on lines of their own, each shown as ``one_line`` shows it.

    Graphviz reads ``\n`` in a label as a line break and ``\\`` as a backslash, so the
    escapes are written with their backslash doubled: they are shown, not obeyed.
    """
    shown = (one_line(p).replace("\\", "\\\\").replace('"', '\\"') for p in parts)
    return '"' + "\\n".join(shown) + '"'


def graph_dot(graph: RosGraph) -> str:
    """Graphviz: nodes as ellipses, topics as boxes, arrows along the data flow."""
    lines = ["digraph rosgraph {", "  rankdir=LR;"]
    for node in graph.nodes:
        lines.append(
            f"  {_dot_id('n:' + node.name)} [label={_dot_label(node.name)}, shape=ellipse];"
        )
    for topic in graph.topics:
        label = _dot_label(topic.name, topic.type)
        lines.append(f"  {_dot_id('t:' + topic.name)} [label={label}, shape=box];")
    for topic in graph.topics:
        tid = _dot_id("t:" + topic.name)
        lines += [f"  {_dot_id('n:' + p)} -> {tid};" for p in topic.publishers]
        lines += [f"  {tid} -> {_dot_id('n:' + s)};" for s in topic.subscribers]
    lines.append("}")
    return "\n".join(lines)


@command("graph")
def graph_cmd(
    ctx: typer.Context,
    all_: Annotated[
        bool,
        typer.Option("-a", "--all", help="Include /rosout, /rosout_agg and the rosout node."),
    ] = False,
    fmt: Annotated[
        GraphFormat | None,
        typer.Option(
            "--format",
            "-F",
            help="text (a tree), json, yaml or dot (Graphviz).",
            show_default=False,
        ),
    ] = None,
    out: Annotated[
        Path | None,
        typer.Option(
            "--output",
            "-o",
            help="Draw into a file through Graphviz's dot: .svg, .png, .pdf (.dot: the DOT).",
            show_default=False,
        ),
    ] = None,
) -> None:
    """Nodes and the topics between them, like rqt_graph, from the master's registrations."""
    from rostools.rosgraph.state import build_graph, system_state

    if out is not None:
        _picture_kind(out)  # a bad name fails before the master is asked
    proxy = master(ctx, TOOL)
    graph = build_graph(system_state(proxy), proxy.topic_types(), include_debug=all_)
    if out is not None:
        draw(graph_dot(graph) + "\n", out)
        return
    chosen = fmt if fmt is not None else GraphFormat(settings(ctx).format.value)
    if chosen is GraphFormat.dot:
        output.put(graph_dot(graph) + "\n")
    elif chosen is GraphFormat.text:
        if graph.nodes:
            output.put(graph_text(graph) + "\n")
        else:
            warn("no nodes are registered")
    else:
        emit(Format(chosen.value), graph.to_data())


def _picture_kind(path: Path) -> str | None:
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

    kind = _picture_kind(path)
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
