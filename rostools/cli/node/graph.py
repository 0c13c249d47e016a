"""``rostools node graph``: the graph as a tree of nodes and topics, as Graphviz, or a picture.

``-o graph.svg`` (or .png, .pdf) draws the DOT through Graphviz's ``dot`` (``cli/graphviz.py``),
rqt_graph's picture without a GUI.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated

import typer

from rostools.cli.common import master
from rostools.cli.declare import command
from rostools.cli.graphviz import (
    GraphFormatOpt,
    PictureOpt,
    dot_id,
    dot_label,
    picture_kind,
    show_graph,
)
from rostools.errors import one_line

if TYPE_CHECKING:
    from rostools.rosgraph.state import RosGraph


from rostools.cli.node.shared import TOOL, warn


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


def graph_dot(graph: RosGraph) -> str:
    """Graphviz: nodes as ellipses, topics as boxes, arrows along the data flow."""
    lines = ["digraph rosgraph {", "  rankdir=LR;"]
    for node in graph.nodes:
        lines.append(f"  {dot_id('n:' + node.name)} [label={dot_label(node.name)}, shape=ellipse];")
    for topic in graph.topics:
        label = dot_label(topic.name, topic.type)
        lines.append(f"  {dot_id('t:' + topic.name)} [label={label}, shape=box];")
    for topic in graph.topics:
        tid = dot_id("t:" + topic.name)
        lines += [f"  {dot_id('n:' + p)} -> {tid};" for p in topic.publishers]
        lines += [f"  {tid} -> {dot_id('n:' + s)};" for s in topic.subscribers]
    lines.append("}")
    return "\n".join(lines)


@command("graph")
def graph_cmd(
    ctx: typer.Context,
    all_: Annotated[
        bool,
        typer.Option("-a", "--all", help="Include /rosout, /rosout_agg and the rosout node."),
    ] = False,
    fmt: GraphFormatOpt = None,
    out: PictureOpt = None,
) -> None:
    """Nodes and the topics between them, like rqt_graph, from the master's registrations."""
    from rostools.rosgraph.state import build_graph, system_state

    if out is not None:
        picture_kind(out)  # a bad name fails before the master is asked
    proxy = master(ctx, TOOL)
    graph = build_graph(system_state(proxy), proxy.topic_types(), include_debug=all_)

    def text() -> str | None:
        if graph.nodes:
            return graph_text(graph)
        warn("no nodes are registered")
        return None

    show_graph(
        ctx, fmt, out, dot=lambda: graph_dot(graph), text=text, data=graph.to_data
    )  # fmt: skip
