"""``rostools node list|info|machine``: who is in the graph, and what each node does.

Text follows rosnode line for line; ``--format json`` gives one document. Typer-free
(``rostools.cli.declare``): the launcher runs list and info without Typer.
"""

from __future__ import annotations

from rostools.cli import output
from rostools.cli.declare import command
from rostools.cli.node.shared import graph, resolve_node, worst
from rostools.cli.output import Format, emit, lines
from rostools.errors import NotFoundError, RostoolsError, one_line
from rostools.rosgraph.masterapi import NODE_TIMEOUT

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from typing import Annotated, Any

    import typer

    from rostools.cli.common import FormatOpt
    from rostools.cli.node.options import TimeoutOpt
    from rostools.cli.settings import Settings
    from rostools.rosgraph.nodeapi import BusConnection, NodeInfo


@command("list", quick=True)
def list_nodes(
    s: Settings,
    namespace: Annotated[
        str | None, typer.Argument(help="Only nodes in this namespace.", show_default=False)
    ] = None,
    uris: Annotated[bool, typer.Option("-u", help="XML-RPC URIs instead of names.")] = False,
    all_: Annotated[bool, typer.Option("-a", "--all", help="URI and name of each node.")] = False,
    fmt: FormatOpt = None,
) -> None:
    """List the nodes registered on the master, sorted."""
    known = graph(s)
    ns = resolve_node(namespace) if namespace else None
    nodes = known.state().nodes(ns)
    out = s.output_format(fmt)
    if all_:
        rows = [{"name": n, "uri": known.uri(n)} for n in nodes]
        emit(
            out,
            rows,
            lambda rs: "\n".join(
                f"{one_line(r['uri'] or 'unknown address')} \t{one_line(r['name'])}" for r in rs
            ),
        )
    elif uris:
        addresses = [known.uri(n) for n in nodes]
        emit(out, addresses, lambda us: lines(u or "unknown address" for u in us))
    else:
        emit(out, nodes, lines)


@command(quick=True)
def info(
    s: Settings,
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

    known = graph(s, timeout)
    names = [resolve_node(n) for n in nodes]
    unknown = [n for n in names if known.uri(n) is None]
    if unknown:
        raise NotFoundError(
            f"unknown node{'s' if len(unknown) > 1 else ''} {', '.join(unknown)}",
            hint="see 'rostools node list'",
        )
    out = s.output_format(fmt)
    results: list[dict[str, Any]] = []
    errors: list[RostoolsError] = []
    for name in names:
        found = node_info(known, name, contact=not quiet)
        if found.error is not None:
            errors.append(found.error)
        if out is Format.text:
            output.put(info_text(found))
            output.flush()
        results.append(found.to_data())
    if out is not Format.text:
        emit(out, results[0] if len(results) == 1 else results)
    if errors:
        raise worst(errors, "could not contact")


@command()
def machine(
    s: Settings,
    name: Annotated[
        str | None,
        typer.Argument(help="A host name or address: list its nodes.", show_default=False),
    ] = None,
    fmt: FormatOpt = None,
) -> None:
    """The hosts the nodes run on; with a host, the nodes that run on it."""
    from rostools.rosgraph.machines import machines, nodes_on_machine

    known = graph(s)
    uris = {n: known.uri(n) for n in known.state().nodes()}
    out = s.output_format(fmt)
    if name is None:
        hosts = machines(uris)
        emit(
            out,
            [{"host": h, "nodes": ns} for h, ns in hosts.items()],
            lambda rows: lines(r["host"] for r in rows),
        )
    else:
        emit(out, nodes_on_machine(uris, name), lines)


def _section(title: str, items: list[str]) -> str:
    if not items:
        return f"{title}: None\n"
    return f"{title}: \n" + "".join(f"{one_line(item)}\n" for item in items)


def master_info_text(info: NodeInfo) -> str:
    """The registration part of rosnode info: publications, subscriptions, services."""
    return (
        f"Node [{one_line(info.name)}]\n"
        + _section("Publications", [f" * {t} [{ty}]" for t, ty in info.publications])
        + "\n"
        + _section("Subscriptions", [f" * {t} [{ty}]" for t, ty in info.subscriptions])
        + "\n"
        + _section("Services", [f" * {s}" for s in info.services])
    )


def connection_text(conn: BusConnection, peer_name: str | None) -> str:
    """One connection as rosnode prints it (a live one; rosnode skips the others).

    Every field is the node's own answer (getBusInfo), so each line is escaped whole.
    """
    peer = f"{peer_name} ({conn.peer})" if peer_name else conn.peer
    direction = f"    * direction: {conn.direction}"
    if conn.local_port is not None:
        direction += f" ({conn.local_port} - {conn.remote}) [{conn.socket}]"
    parts = (f" * topic: {conn.topic}", f"    * to: {peer}", direction,
             f"    * transport: {conn.transport}")  # fmt: skip
    return "".join(one_line(line) + "\n" for line in parts)


def info_text(info: NodeInfo) -> str:
    """A node's info as rosnode prints it, with the node's own part when it was contacted."""
    text = "-" * 80 + "\n" + master_info_text(info) + "\n"
    uri = one_line(info.uri)
    if info.error is not None:
        text += f"\ncontacting node {uri} ...\n"  # the error follows on stderr
    elif info.pid is not None and info.connections is not None:
        text += f"\ncontacting node {uri} ...\nPid: {info.pid}\n"
        if info.connections:
            text += "Connections:\n" + "".join(
                connection_text(c, name) for c, name in info.connections if c.connected
            )
        text += "\n"
    return text
