"""``rostools node ping``: call a node's getPid, once a second, as rosnode ping."""

from __future__ import annotations

import time
from collections.abc import Iterator
from typing import TYPE_CHECKING, Annotated

import typer

from rostools.cli import output
from rostools.cli.common import FormatOpt, output_format, settings
from rostools.cli.declare import command
from rostools.cli.output import Format
from rostools.errors import (
    NotFoundError,
    RostoolsError,
    TimeoutExpired,
    UnreachableError,
    UsageError,
    one_line,
)

if TYPE_CHECKING:
    from rostools.rosgraph.nodeapi import Graph


from rostools.cli.node.options import TimeoutOpt
from rostools.cli.node.shared import failure_class, graph as node_graph, resolve_node, warn
from rostools.rosgraph.masterapi import NODE_TIMEOUT

#: Seconds between two pings of one node, as rosnode.
PING_INTERVAL = 1.0


def reply_text(uri: str, ms: float) -> str:
    """A reply line as rosnode prints it."""
    return f"xmlrpc reply from {one_line(uri)}\ttime={ms:f}ms"


def _ping_replies(graph: Graph, node: str, count: int | None) -> Iterator[tuple[str, int, float]]:
    """Ping ``node`` until ``count`` replies (or forever); yields (uri, pid, ms).

    When the node refuses the connection, its URI is looked up again once, as rosnode does:
    a node restarted under the same name has a new port.
    """
    uri = graph.require_uri(node)
    sent = 0
    retried = False
    while count is None or sent < count:
        if sent:
            time.sleep(PING_INTERVAL)
        try:
            pid, ms = graph.api(node, uri).ping()
        except UnreachableError:
            new = graph.uri(node, refresh=True)
            if new is None:
                raise NotFoundError(f"unknown node {node}: it has left the master") from None
            if new == uri or retried:
                raise
            warn(f"node {node} moved from {uri} to {new}; pinging again")
            uri, retried = new, True
            continue
        sent += 1
        yield uri, pid, ms


@command()
def ping(
    ctx: typer.Context,
    node: Annotated[str | None, typer.Argument(help="Node name.", show_default=False)] = None,
    count: Annotated[
        int | None,
        typer.Option(
            "-c", "--count", min=1, help="Stop after COUNT replies (default: until Ctrl-C)."
        ),
    ] = None,
    all_: Annotated[bool, typer.Option("-a", "--all", help="Ping every node once.")] = False,
    timeout: TimeoutOpt = NODE_TIMEOUT,
    fmt: FormatOpt = None,
) -> None:
    """Call a node's getPid once a second and print the round-trip times."""
    if all_ and node:
        raise UsageError(f"give a node name or -a/--all, not both (got {node})")
    if all_ and count is not None:
        raise UsageError("-c may not be used with --all")
    if not all_ and not node:
        raise UsageError("give a node name, or -a/--all to ping every node")
    fmt = output_format(ctx, fmt)
    graph = node_graph(settings(ctx), timeout)
    if all_:
        _ping_all(graph, fmt)
        return
    assert node is not None
    name = resolve_node(node)
    graph.require_uri(name)
    if fmt is Format.text:
        shown = one_line(name)
        output.line(
            f"rosnode: node is [{shown}]\npinging {shown} with a timeout of {timeout}s", flush=True
        )
    times: list[float] = []
    try:
        for seq, (uri, pid, ms) in enumerate(_ping_replies(graph, name, count), 1):
            times.append(ms)
            _print_reply(fmt, name, uri, pid, ms, seq)
    except KeyboardInterrupt:
        pass  # asked to run until Ctrl-C: a normal end
    if fmt is Format.text and len(times) > 1:
        output.line(f"ping average: {sum(times) / len(times):f}ms")


def _print_reply(fmt: Format, node: str, uri: str, pid: int, ms: float, seq: int) -> None:
    from rostools.cli import output

    data = {"node": node, "uri": uri, "seq": seq, "pid": pid, "time_ms": round(ms, 6)}
    output.write(fmt, data, lambda _: reply_text(uri, ms))


def _ping_all(graph: Graph, fmt: Format) -> None:
    nodes = graph.state().nodes()
    if fmt is Format.text:
        output.line(
            "Will ping the following nodes: \n" + "".join(f" * {one_line(n)}\n" for n in nodes)
        )
    errors: list[RostoolsError] = []
    failed: list[str] = []
    for name in nodes:
        if graph.uri(name) is None:
            continue  # it left between the two calls to the master
        if fmt is Format.text:
            output.line(f"pinging {one_line(name)} with a timeout of {graph.timeout}s", flush=True)
        try:
            for uri, pid, ms in _ping_replies(graph, name, 1):
                _print_reply(fmt, name, uri, pid, ms, 1)
        except (UnreachableError, TimeoutExpired, NotFoundError) as err:
            warn(str(err))
            errors.append(err)
            failed.append(name)
    if errors:
        raise failure_class(errors)(
            f"{len(errors)} of {len(nodes)} nodes did not answer: {', '.join(failed)}"
        )
