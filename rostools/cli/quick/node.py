"""``node list|info`` without Typer (see ``rostools.cli.quick``), and what node commands share.

Text follows rosnode line for line; ``--format json`` gives one document.
"""

from __future__ import annotations

import sys

from rostools.cli.output import Format, emit, lines
from rostools.errors import (
    NotFoundError,
    RostoolsError,
    TimeoutExpired,
    UnreachableError,
    one_line,
)
from rostools.names import script_resolve

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from typing import Any

    from rostools.cli.settings import Settings
    from rostools.rosgraph.nodeapi import BusConnection, Graph, NodeInfo

TOOL = "rosnode"


def graph(s: Settings, timeout: float) -> Graph:
    """The graph as a node command sees it: the master, and nodes asked with ``timeout``."""
    from rostools.rosgraph.nodeapi import Graph

    return Graph(s.master(TOOL), timeout)


def resolve_node(name: str) -> str:
    """A node name from the command line, resolved as rosnode does."""
    return script_resolve(name, TOOL)


def list_nodes(
    s: Settings, namespace: str | None, uris: bool, all_: bool, fmt: Format | str | None
) -> None:
    """List the nodes registered on the master, sorted."""
    from rostools.rosgraph.masterapi import NODE_TIMEOUT

    known = graph(s, NODE_TIMEOUT)
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


def failure_class(errors: list[RostoolsError]) -> type[RostoolsError]:
    """The error class (so the exit code) for several nodes' failures.

    Each kind alone keeps its own code (not found 3, timeout 5); a mix is "unreachable" (4),
    the code for a node that cannot be talked to.
    """
    for kind in (NotFoundError, TimeoutExpired):
        if all(isinstance(e, kind) for e in errors):
            return kind
    return UnreachableError


def worst(errors: list[RostoolsError], what: str) -> RostoolsError:
    """One error for several failures: the first's, or a summary with the right exit code."""
    if len(errors) == 1:
        return errors[0]
    return failure_class(errors)(
        f"{what} {len(errors)} nodes: " + "; ".join(str(e) for e in errors)
    )


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


def info(
    s: Settings, nodes: list[str], quiet: bool, timeout: float, fmt: Format | str | None
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
            sys.stdout.write(info_text(found))
            sys.stdout.flush()
        results.append(found.to_data())
    if out is not Format.text:
        emit(out, results[0] if len(results) == 1 else results)
    if errors:
        raise worst(errors, "could not contact")
