"""``rostools node list|info|machine``: who is in the graph, and what each node does.

Text follows rosnode line for line; ``--format json`` gives one document.
"""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rostools.cli.common import FormatOpt, output_format, settings
from rostools.cli.output import Format, emit
from rostools.cli.quick import node as quick
from rostools.cli.quick import runs
from rostools.errors import (
    NotFoundError,
    RostoolsError,
)

if TYPE_CHECKING:
    from rostools.rosgraph.nodeapi import BusConnection, NodeInfo


from rostools.cli.node.group import TimeoutOpt, app, node_graph, worst
from rostools.cli.quick.node import resolve_node
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


def _section(title: str, items: list[str]) -> str:
    if not items:
        return f"{title}: None\n"
    return f"{title}: \n" + "".join(f"{item}\n" for item in items)


def master_info_text(info: NodeInfo) -> str:
    """The registration part of rosnode info: publications, subscriptions, services."""
    return (
        f"Node [{info.name}]\n"
        + _section("Publications", [f" * {t} [{ty}]" for t, ty in info.publications])
        + "\n"
        + _section("Subscriptions", [f" * {t} [{ty}]" for t, ty in info.subscriptions])
        + "\n"
        + _section("Services", [f" * {s}" for s in info.services])
    )


def connection_text(conn: BusConnection, peer_name: str | None) -> str:
    """One connection as rosnode prints it (a live one; rosnode skips the others)."""
    peer = f"{peer_name} ({conn.peer})" if peer_name else conn.peer
    direction = f"    * direction: {conn.direction}"
    if conn.local_port is not None:
        direction += f" ({conn.local_port} - {conn.remote}) [{conn.socket}]"
    return (
        f" * topic: {conn.topic}\n"
        f"    * to: {peer}\n"
        f"{direction}\n"
        f"    * transport: {conn.transport}\n"
    )


def info_text(info: NodeInfo) -> str:
    """A node's info as rosnode prints it, with the node's own part when it was contacted."""
    text = "-" * 80 + "\n" + master_info_text(info) + "\n"
    if info.error is not None:
        text += f"\ncontacting node {info.uri} ...\n"  # the error follows on stderr
    elif info.pid is not None and info.connections is not None:
        text += f"\ncontacting node {info.uri} ...\nPid: {info.pid}\n"
        if info.connections:
            text += "Connections:\n" + "".join(
                connection_text(c, name) for c, name in info.connections if c.connected
            )
        text += "\n"
    return text


@app.command()
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
    from rostools.rosgraph.nodeapi import node_info

    graph = node_graph(ctx, timeout)
    names = [resolve_node(n) for n in nodes]
    unknown = [n for n in names if graph.uri(n) is None]
    if unknown:
        raise NotFoundError(
            f"unknown node{'s' if len(unknown) > 1 else ''} {', '.join(unknown)}",
            hint="see 'rostools node list'",
        )
    fmt = output_format(ctx, fmt)
    results: list[dict[str, Any]] = []
    errors: list[RostoolsError] = []
    for name in names:
        found = node_info(graph, name, contact=not quiet)
        if found.error is not None:
            errors.append(found.error)
        if fmt is Format.text:
            sys.stdout.write(info_text(found))
            sys.stdout.flush()
        results.append(found.to_data())
    if fmt is not Format.text:
        emit(fmt, results[0] if len(results) == 1 else results)
    if errors:
        raise worst(errors, "could not contact")


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
            lambda rows: "\n".join(r["host"] for r in rows),
        )
    else:
        emit(fmt, nodes_on_machine(uris, name), "\n".join)
