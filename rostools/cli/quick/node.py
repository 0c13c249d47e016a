"""``node list`` without Typer (see ``rostools.cli.quick``)."""

from __future__ import annotations

from rostools.cli.output import Format, emit
from rostools.names import script_resolve

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from rostools.cli.settings import Settings
    from rostools.rosgraph.nodeapi import Graph

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
            lambda rs: "\n".join(f"{r['uri'] or 'unknown address'} \t{r['name']}" for r in rs),
        )
    elif uris:
        addresses = [known.uri(n) for n in nodes]
        emit(out, addresses, lambda us: "\n".join(u or "unknown address" for u in us))
    else:
        emit(out, nodes, "\n".join)
