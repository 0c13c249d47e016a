"""``node list`` without Typer (see ``rostools.cli.quick``)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from rostools.cli.output import Format, emit
from rostools.names import script_resolve

if TYPE_CHECKING:
    from rostools.cli.settings import Settings


def list_nodes(
    s: Settings, namespace: str | None, uris: bool, all_: bool, fmt: Format | str | None
) -> None:
    """List the nodes registered on the master, sorted."""
    from rostools.rosgraph.masterapi import NODE_TIMEOUT
    from rostools.rosgraph.nodeapi import Graph

    graph = Graph(s.master("rosnode"), NODE_TIMEOUT)
    ns = script_resolve(namespace, "rosnode") if namespace else None
    nodes = graph.state().nodes(ns)
    out = s.output_format(fmt)
    if all_:
        rows = [{"name": n, "uri": graph.uri(n)} for n in nodes]
        emit(
            out,
            rows,
            lambda rs: "\n".join(f"{r['uri'] or 'unknown address'} \t{r['name']}" for r in rs),
        )
    elif uris:
        found = [graph.uri(n) for n in nodes]
        emit(out, found, lambda us: "\n".join(u or "unknown address" for u in us))
    else:
        emit(out, nodes, "\n".join)
