"""``rostools node kill|cleanup``: stop nodes, and purge those that no longer answer."""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rostools.cli import output
from rostools.cli.common import FormatOpt, output_format, settings
from rostools.cli.declare import command
from rostools.cli.output import Format, emit, lines
from rostools.errors import (
    NotFoundError,
    UsageError,
    one_line,
)

if TYPE_CHECKING:
    from rostools.rosgraph.nodeapi import Probe


from rostools.cli.node.options import TimeoutOpt
from rostools.cli.node.shared import graph as node_graph, resolve_node, warn, worst
from rostools.rosgraph.masterapi import NODE_TIMEOUT


def _choose(known: list[str]) -> list[str]:
    """rosnode kill's menu on a terminal: the node whose number is typed (none if none run)."""
    if not known:
        return []
    output.line(lines(f"{i}. {n}" for i, n in enumerate(known, 1)))
    output.line("\nPlease enter the number of the node you wish to kill.")
    while True:
        try:
            answer = input("> ").strip()
        except EOFError:  # Ctrl-D
            raise UsageError("no node chosen") from None
        if answer.isdigit() and 1 <= int(answer) <= len(known):
            return [known[int(answer) - 1]]
        output.line(f"ERROR: enter a number from 1 to {len(known)} (Ctrl-C to cancel)")


@command()
def kill(
    ctx: typer.Context,
    nodes: Annotated[
        list[str] | None, typer.Argument(help="Node names.", show_default=False)
    ] = None,
    all_: Annotated[bool, typer.Option("-a", "--all", help="Kill every node.")] = False,
    timeout: TimeoutOpt = NODE_TIMEOUT,
    fmt: FormatOpt = None,
) -> None:
    """Ask nodes to shut down (their shutdown call, reason "user request").

    With no names on a terminal, pick one from a numbered menu, as rosnode kill.
    """
    from rostools.rosgraph.nodeapi import kill_nodes

    if all_ and nodes:
        raise UsageError("give node names or -a/--all, not both")
    menu = not all_ and not nodes
    if menu and not (sys.stdin.isatty() and sys.stdout.isatty()):
        raise UsageError("give the nodes to kill, or -a/--all to kill every node")
    graph = node_graph(settings(ctx), timeout)
    known = graph.state().nodes()
    if menu:
        names = _choose(sorted(known))
    elif all_:
        names = known
    else:
        names = list(dict.fromkeys(resolve_node(n) for n in nodes or []))
        unknown = [n for n in names if n not in known]
        if unknown:
            raise NotFoundError(
                f"unknown node{'s' if len(unknown) > 1 else ''} {', '.join(unknown)}",
                hint="see 'rostools node list'",
            )
    fmt = output_format(ctx, fmt)
    if not names:
        warn("no nodes are running")
        if fmt is not Format.text:
            emit(fmt, {"killed": [], "failed": []})
        return
    if fmt is Format.text:
        if len(names) > 1:
            output.line("killing:\n" + lines(f" * {n}" for n in names), flush=True)
        else:
            output.line(f"killing {one_line(names[0])}", flush=True)
    result = kill_nodes(graph, names)
    if fmt is Format.text:
        if result.killed:
            output.line("killed")
    else:
        failed = [{"node": n, "error": str(e)} for n, e in result.failed]
        emit(fmt, {"killed": result.killed, "failed": failed})
    if result.failed:
        raise worst([e for _, e in result.failed], "could not kill")


def _confirm() -> bool:
    """Ask y/n on stdin, as rosnode does; the end of stdin means no (rosnode loops forever)."""
    sys.stderr.write("Please type y or n to continue: ")
    sys.stderr.flush()
    while True:
        line = sys.stdin.readline()
        if not line:
            return False
        answer = line.strip().lower()
        if answer in ("y", "yes", "n", "no"):
            return answer.startswith("y")
        sys.stderr.write("Please type y or n: ")
        sys.stderr.flush()


def unreachable_text(dead: list[Probe]) -> str:
    """The nodes that did not answer (and why), as rosnode lists them."""
    return "Unable to contact the following nodes:\n" + "".join(
        one_line(f" * {p.node} ({p.error})") + "\n" for p in dead
    )


@command()
def cleanup(
    ctx: typer.Context,
    yes: Annotated[bool, typer.Option("-y", "--yes", help="Purge without asking.")] = False,
    dry_run: Annotated[
        bool, typer.Option("-n", "--dry-run", help="Only list the unreachable nodes.")
    ] = False,
    timeout: TimeoutOpt = NODE_TIMEOUT,
    fmt: FormatOpt = None,
) -> None:
    """Purge the registrations of nodes that do not answer a ping from the master."""
    from rostools.rosgraph.cleanup import apply_cleanup, plan_cleanup, service_apis
    from rostools.rosgraph.nodeapi import probe_nodes

    graph = node_graph(settings(ctx), timeout)
    state = graph.state()
    dead = [p for p in probe_nodes(graph, state.nodes()) if not p.alive]
    fmt = output_format(ctx, fmt)
    data: dict[str, Any] = {
        "unreachable": [{"node": p.node, "uri": p.uri, "error": str(p.error)} for p in dead],
        "unregistered": [],
        "purged": False,
    }
    if not dead:
        if fmt is Format.text:
            warn("every node answered: nothing to clean up")
        else:
            emit(fmt, data)
        return
    if fmt is Format.text:
        output.put(unreachable_text(dead))
        output.flush()
    if not dry_run and not yes:
        # asked as rosnode asks: the answer comes from stdin, a terminal or a pipe (echo y |)
        sys.stderr.write(
            "Warning: these might include alive and functioning nodes, e.g. in unstable "
            "networks.\nCleanup will purge all information about these nodes from the master.\n"
        )
        if not _confirm():
            warn("aborted: nothing was changed")
            dry_run = True
    if not dry_run:
        nodes = {p.node: p.uri for p in dead if p.uri}
        plan = plan_cleanup(state, nodes, service_apis(graph, nodes))
        done = apply_cleanup(settings(ctx).resolved_master_uri(), plan)
        data["purged"] = True
        data["unregistered"] = [
            {"node": s.node, "kind": s.kind, "name": s.name, "removed": ok}
            for s, ok in zip(plan, done, strict=True)
        ]
        if fmt is Format.text:
            for node in sorted(nodes):
                output.line(f"Unregistering {one_line(node)}")
            output.line("done")
    if fmt is not Format.text:
        emit(fmt, data)
