"""``rostools tf frames``: the tree of frames, as ``view_frames`` draws it (live or from a bag).

Live, ``/tf`` and ``/tf_static`` are heard for ``--wait`` seconds (view_frames' 5), into edges
kept as tf2's buffer keeps them (``rostools.tf.edges``); from a bag, every TF message of the
recording is fed in order, and the tree is the one a tf2 buffer holds at its end. Each edge
carries view_frames' label: broadcaster, average rate, buffer length, most recent and oldest
transform.
"""

from __future__ import annotations

import time
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from rostools.cli.common import FINITE, node_session
from rostools.cli.declare import command
from rostools.cli.graphviz import (
    GraphFormatOpt,
    PictureOpt,
    dot_id,
    dot_label,
    picture_kind,
    show_graph,
)
from rostools.cli.tf.options import BagOpt
from rostools.errors import NotFoundError, UsageError, one_line
from rostools.tf.edges import Edge, Edges, shown_broadcaster

if TYPE_CHECKING:
    import asyncio

    from rostools.node.node import LiveNode

#: How long the live tree is heard by default (view_frames' 5 s).
WAIT = 5.0


def _number(value: float) -> str:
    """A number as view_frames shows it: tf2's three decimals, read back by YAML as a float."""
    return str(float(f"{value:.3f}"))


def edge_label(edge: Edge) -> list[str]:
    """The lines of view_frames' label on one edge."""
    return [
        f"Broadcaster: {edge.broadcaster}",
        f"Average rate: {_number(edge.rate)}",
        f"Buffer length: {_number(edge.span)}",
        f"Most recent transform: {_number(edge.newest_ns / 1e9)}",
        f"Oldest transform: {_number(edge.oldest_ns / 1e9)}",
    ]


def frames_dot(edges: Edges, at_ns: int) -> str:
    """Graphviz: a frame a node, an edge per child with view_frames' label, and its legend."""
    lines = ["digraph G {"]
    for edge in edges.edges():
        label = dot_label(*edge_label(edge))
        lines.append(f"  {dot_id(edge.parent)} -> {dot_id(edge.child)} [label={label}];")
    lines.append("  edge [style=invis];")
    lines.append('  subgraph cluster_legend { style=bold; color=black; label="view_frames Result";')
    stamp = dot_label(f"Recorded at time: {at_ns / 1e9:.3f}")
    lines.append(f"    {stamp} [shape=plaintext];")
    lines.append("  }")
    lines += [f"  {stamp} -> {dot_id(root)};" for root in edges.roots()]
    lines.append("}")
    return "\n".join(lines)


def frames_text(edges: Edges) -> str:
    """Each tree from its root, an edge a line: the child, its broadcaster, rate and age."""
    children = edges.children()
    lines: list[str] = []

    def walk(frame: str, stem: str, seen: set[str]) -> None:
        kids = children.get(frame, [])
        for i, child in enumerate(kids):
            last = i == len(kids) - 1
            edge = edges.by_child[child]
            rate = f"{edge.rate:.1f} Hz, {edge.span:.3f} s buffered"
            about = "static" if edge.static else rate
            lines.append(
                f"{stem}{'└── ' if last else '├── '}{one_line(child)}"
                f"  [{one_line(shown_broadcaster(edge.broadcaster))}, {about}]"
            )
            if child not in seen:  # a loop is shown once, where it closes
                walk(child, stem + ("    " if last else "│   "), seen | {child})

    roots = edges.roots() or [min(edges.by_child)]  # a tree that is all loop has no root
    for root in roots:
        lines.append(one_line(root))
        walk(root, "", {root})
    return "\n".join(lines)


def frames_data(edges: Edges) -> dict[str, object]:
    """The tree as data: the frames, and each edge with its numbers."""
    return {"frames": edges.frames(), "edges": [e.to_data() for e in edges.edges()]}


@command()
def frames(
    ctx: typer.Context,
    bag: BagOpt = None,
    out: PictureOpt = None,
    wait: Annotated[
        float,
        typer.Option(
            "--wait", "-w", click_type=FINITE, help="Seconds to listen (live; view_frames' 5)."
        ),
    ] = WAIT,
    fmt: GraphFormatOpt = None,
) -> None:
    """Draw the tree of frames, as view_frames, with each edge's broadcaster and rate."""
    if out is not None:
        picture_kind(out)  # a bad name fails before anything is heard
    if not wait > 0:
        raise UsageError("--wait must be a number of seconds above 0")
    if bag is not None:
        edges, at_ns = _from_bag(bag)
    else:
        edges = node_session(ctx, partial(_listen, wait), "view_frames")
        at_ns = time.time_ns()
    if not edges.by_child:
        where = f"in {bag}" if bag is not None else f"within {wait:g} s"
        raise NotFoundError(f"no tf data received {where}")
    show_graph(
        ctx,
        fmt,
        out,
        dot=lambda: frames_dot(edges, at_ns),
        text=lambda: frames_text(edges),
        data=lambda: frames_data(edges),
    )


def _from_bag(path: Path) -> tuple[Edges, int]:
    """The edges a tf2 buffer holds at the end of the recording, and that end's time."""
    from rostools.cli.tf.shared import open_feed

    edges = Edges()
    with open_feed(path) as feed:
        for batch in feed.batches():
            edges.add(batch.transforms, batch.broadcaster, batch.static)
        return edges, feed.end_ns or 0


async def _listen(wait: float, node: LiveNode, stop: asyncio.Event) -> Edges:
    """The edges heard on ``/tf`` and ``/tf_static`` for ``wait`` s (or until stopped)."""
    from rostools.cli.tf.shared import LiveFeed
    from rostools.node.session import first

    edges = Edges()
    feed = LiveFeed(node, lambda b: edges.add(b.transforms, b.broadcaster, b.static))
    await feed.start()
    await first(stop.wait(), timeout=wait)
    await feed.close()
    return edges
