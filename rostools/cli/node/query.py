"""``rostools node list|info|machine``: who is in the graph, and what each node does.

Text follows rosnode line for line; ``--format json`` gives one document.
"""

from __future__ import annotations

from typing import Annotated

import typer

from rostools.cli.common import FormatOpt, output_format, settings
from rostools.cli.node.group import TimeoutOpt, app, node_graph
from rostools.cli.output import emit, lines
from rostools.cli.quick import node as quick
from rostools.cli.quick import runs
from rostools.rosgraph.masterapi import NODE_TIMEOUT


@app.command("list")
@runs(quick.list_nodes)
def list_nodes(
    ctx: typer.Context,
    namespace: Annotated[
        str | None, typer.Argument(help="Only nodes in this namespace.", show_default=False)
    ] = None,
    uris: Annotated[bool, typer.Option("-u", help="XML-RPC URIs instead of names.")] = False,
    all_: Annotated[bool, typer.Option("-a", "--all", help="URI and name of each node.")] = False,
    fmt: FormatOpt = None,
) -> None:
    """List the nodes registered on the master, sorted."""
    quick.list_nodes(settings(ctx), namespace, uris, all_, fmt)


@app.command()
@runs(quick.info)
def info(
    ctx: typer.Context,
    nodes: Annotated[list[str], typer.Argument(help="Node names.", show_default=False)],
    quiet: Annotated[
        bool,
        typer.Option("-q", "--quiet", help="Only what the master knows; do not contact the nodes."),
    ] = False,
    timeout: TimeoutOpt = NODE_TIMEOUT,
    fmt: FormatOpt = None,
) -> None:
    """Publications, subscriptions and services of nodes, and their pid and live connections."""
    quick.info(settings(ctx), nodes, quiet, timeout, fmt)


@app.command()
def machine(
    ctx: typer.Context,
    name: Annotated[
        str | None,
        typer.Argument(help="A host name or address: list its nodes.", show_default=False),
    ] = None,
    fmt: FormatOpt = None,
) -> None:
    """The hosts the nodes run on; with a host, the nodes that run on it."""
    from rostools.rosgraph.machines import machines, nodes_on_machine

    graph = node_graph(ctx)
    uris = {n: graph.uri(n) for n in graph.state().nodes()}
    fmt = output_format(ctx, fmt)
    if name is None:
        hosts = machines(uris)
        emit(
            fmt,
            [{"host": h, "nodes": ns} for h, ns in hosts.items()],
            lambda rows: lines(r["host"] for r in rows),
        )
    else:
        emit(fmt, nodes_on_machine(uris, name), lines)
