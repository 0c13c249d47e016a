"""``rostools node``: rosnode's list, info, ping, kill, machine and cleanup, and ``graph``.

Text output follows rosnode line for line where rosnode has a command; ``--format json``
gives one document (``ping``: one object per reply). Unlike rosnode, an unknown node is an
error (exit 3), a node that cannot be reached exits 4 and one that does not answer within
``--timeout`` exits 5.
"""

from __future__ import annotations

import enum
import sys
import time
from collections.abc import Iterator
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rostools.cli.common import FiniteFloat, FormatOpt, master, output_format, settings
from rostools.cli.output import Format, emit
from rostools.errors import (
    NotFoundError,
    RostoolsError,
    TimeoutExpired,
    UnreachableError,
    UsageError,
)
from rostools.names import script_resolve

if TYPE_CHECKING:
    from rostools.rosgraph.introspect import BusConnection, Graph, NodeInfo, Probe, RosGraph

app = typer.Typer(
    name="node",
    help="ROS nodes: list, info, ping, kill, machine, cleanup, and graph.",
    no_args_is_help=True,
    add_completion=False,
)

TOOL = "rosnode"
#: Seconds to wait for a node's answer: rosnode's ping timeout.
NODE_TIMEOUT = 3.0
#: Seconds between two pings of one node, as rosnode.
PING_INTERVAL = 1.0

TimeoutOpt = Annotated[
    float,
    typer.Option(
        "--timeout",
        "-t",
        click_type=FiniteFloat(min=0.001),
        help="Seconds to wait for each node's answer.",
    ),
]


def _graph(ctx: typer.Context, timeout: float = NODE_TIMEOUT) -> Graph:
    from rostools.rosgraph.introspect import Graph

    return Graph(master(ctx, TOOL), timeout)


def _resolve(name: str) -> str:
    return script_resolve(name, TOOL)


def _warn(text: str) -> None:
    sys.stderr.write(f"rostools: {text}\n")


# --------------------------------------------------------------------------- list


@app.command("list")
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
    graph = _graph(ctx)
    ns = _resolve(namespace) if namespace else None
    nodes = graph.state().nodes(ns)
    fmt = output_format(ctx, fmt)
    if all_:
        rows = [{"name": n, "uri": graph.uri(n)} for n in nodes]
        emit(
            fmt,
            rows,
            lambda rs: "\n".join(f"{r['uri'] or 'unknown address'} \t{r['name']}" for r in rs),
        )
    elif uris:
        found = [graph.uri(n) for n in nodes]
        emit(fmt, found, lambda us: "\n".join(u or "unknown address" for u in us))
    else:
        emit(fmt, nodes, "\n".join)


# --------------------------------------------------------------------------- info


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
    from rostools.rosgraph.introspect import node_info

    graph = _graph(ctx, timeout)
    names = [_resolve(n) for n in nodes]
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
        raise _worst(errors, "could not contact")


def failure_class(errors: list[RostoolsError]) -> type[RostoolsError]:
    """The error class (so the exit code) for several nodes' failures.

    Each kind alone keeps its own code (not found 3, timeout 5); a mix is "unreachable" (4),
    the code for a node that cannot be talked to.
    """
    for kind in (NotFoundError, TimeoutExpired):
        if all(isinstance(e, kind) for e in errors):
            return kind
    return UnreachableError


def _worst(errors: list[RostoolsError], what: str) -> RostoolsError:
    """One error for several failures: the first's, or a summary with the right exit code."""
    if len(errors) == 1:
        return errors[0]
    return failure_class(errors)(
        f"{what} {len(errors)} nodes: " + "; ".join(str(e) for e in errors)
    )


# --------------------------------------------------------------------------- ping


def reply_text(uri: str, ms: float) -> str:
    """A reply line as rosnode prints it."""
    return f"xmlrpc reply from {uri}\ttime={ms:f}ms"


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
            _warn(f"node {node} moved from {uri} to {new}; pinging again")
            uri, retried = new, True
            continue
        sent += 1
        yield uri, pid, ms


@app.command()
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
    graph = _graph(ctx, timeout)
    if all_:
        _ping_all(graph, fmt)
        return
    assert node is not None
    name = _resolve(node)
    graph.require_uri(name)
    if fmt is Format.text:
        print(f"pinging {name} with a timeout of {timeout}s", flush=True)
    times: list[float] = []
    try:
        for seq, (uri, pid, ms) in enumerate(_ping_replies(graph, name, count), 1):
            times.append(ms)
            _print_reply(fmt, name, uri, pid, ms, seq)
    except KeyboardInterrupt:
        pass  # asked to run until Ctrl-C: a normal end
    if fmt is Format.text and len(times) > 1:
        print(f"ping average: {sum(times) / len(times):f}ms")


def _print_reply(fmt: Format, node: str, uri: str, pid: int, ms: float, seq: int) -> None:
    from rostools.cli import output

    data = {"node": node, "uri": uri, "seq": seq, "pid": pid, "time_ms": round(ms, 6)}
    output.write(fmt, data, lambda _: reply_text(uri, ms))


def _ping_all(graph: Graph, fmt: Format) -> None:
    nodes = graph.state().nodes()
    if fmt is Format.text:
        print("Will ping the following nodes: \n" + "".join(f" * {n}\n" for n in nodes))
    errors: list[RostoolsError] = []
    failed: list[str] = []
    for name in nodes:
        if graph.uri(name) is None:
            continue  # it left between the two calls to the master
        if fmt is Format.text:
            print(f"pinging {name} with a timeout of {graph.timeout}s", flush=True)
        try:
            for uri, pid, ms in _ping_replies(graph, name, 1):
                _print_reply(fmt, name, uri, pid, ms, 1)
        except (UnreachableError, TimeoutExpired, NotFoundError) as err:
            _warn(str(err))
            errors.append(err)
            failed.append(name)
    if errors:
        raise failure_class(errors)(
            f"{len(errors)} of {len(nodes)} nodes did not answer: {', '.join(failed)}"
        )


# --------------------------------------------------------------------------- kill


def _choose(known: list[str]) -> list[str]:
    """rosnode kill's menu on a terminal: the node whose number is typed (none if none run)."""
    if not known:
        return []
    print("\n".join(f"{i}. {n}" for i, n in enumerate(known, 1)))
    print("\nPlease enter the number of the node you wish to kill.")
    while True:
        try:
            answer = input("> ").strip()
        except EOFError:  # Ctrl-D
            raise UsageError("no node chosen") from None
        if answer.isdigit() and 1 <= int(answer) <= len(known):
            return [known[int(answer) - 1]]
        print(f"ERROR: enter a number from 1 to {len(known)} (Ctrl-C to cancel)")


@app.command()
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
    from rostools.rosgraph.introspect import kill_nodes

    if all_ and nodes:
        raise UsageError("give node names or -a/--all, not both")
    menu = not all_ and not nodes
    if menu and not (sys.stdin.isatty() and sys.stdout.isatty()):
        raise UsageError("give the nodes to kill, or -a/--all to kill every node")
    graph = _graph(ctx, timeout)
    known = graph.state().nodes()
    if menu:
        names = _choose(sorted(known))
    elif all_:
        names = known
    else:
        names = list(dict.fromkeys(_resolve(n) for n in nodes or []))
        unknown = [n for n in names if n not in known]
        if unknown:
            raise NotFoundError(
                f"unknown node{'s' if len(unknown) > 1 else ''} {', '.join(unknown)}",
                hint="see 'rostools node list'",
            )
    fmt = output_format(ctx, fmt)
    if not names:
        _warn("no nodes are running")
        if fmt is not Format.text:
            emit(fmt, {"killed": [], "failed": []})
        return
    if fmt is Format.text:
        if len(names) > 1:
            print("killing:\n" + "\n".join(f" * {n}" for n in names), flush=True)
        else:
            print(f"killing {names[0]}", flush=True)
    result = kill_nodes(graph, names)
    if fmt is Format.text:
        if result.killed:
            print("killed")
    else:
        failed = [{"node": n, "error": str(e)} for n, e in result.failed]
        emit(fmt, {"killed": result.killed, "failed": failed})
    if result.failed:
        raise _worst([e for _, e in result.failed], "could not kill")


# --------------------------------------------------------------------------- machine


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
    from rostools.rosgraph.introspect import machines, nodes_on_machine

    graph = _graph(ctx)
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


# --------------------------------------------------------------------------- cleanup


def _confirm() -> bool:
    """Ask y/n on the terminal, as rosnode does; EOF means no."""
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
        f" * {p.node} ({p.error})\n" for p in dead
    )


@app.command()
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
    from rostools.rosgraph.introspect import apply_cleanup, plan_cleanup, probe_nodes, service_apis

    graph = _graph(ctx, timeout)
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
            _warn("every node answered: nothing to clean up")
        else:
            emit(fmt, data)
        return
    if fmt is Format.text:
        sys.stdout.write(unreachable_text(dead))
        sys.stdout.flush()
    if not dry_run and not yes:
        if not sys.stdin.isatty():
            raise UsageError(
                "will not purge without asking, and stdin is not a terminal",
                hint="add -y/--yes to purge, or -n/--dry-run to only list",
            )
        sys.stderr.write(
            "Warning: these might include alive and functioning nodes, e.g. in unstable "
            "networks.\nCleanup will purge all information about these nodes from the master.\n"
        )
        if not _confirm():
            _warn("aborted: nothing was changed")
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
                print(f"Unregistering {node}")
            print("done")
    if fmt is not Format.text:
        emit(fmt, data)


# --------------------------------------------------------------------------- graph


class GraphFormat(str, enum.Enum):
    """Output formats of ``node graph``: the usual ones and Graphviz."""

    text = "text"
    json = "json"
    yaml = "yaml"
    dot = "dot"


def graph_text(graph: RosGraph) -> str:
    """Each node, the topics it publishes and subscribes, and the nodes at the other end."""
    lines: list[str] = []
    for node in graph.nodes:
        lines.append(node.name)
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
                    ", ".join(peers)
                    if peers
                    else ("(no subscribers)" if arrow == "→" else "(no publishers)")
                )
                ty = graph.topic(topic).type
                lines.append(f"{stem}{branch}{topic} [{ty}] {arrow} {others}")
    return "\n".join(lines)


def _dot_id(text: str) -> str:
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"') + '"'


def graph_dot(graph: RosGraph) -> str:
    """Graphviz: nodes as ellipses, topics as boxes, arrows along the data flow."""
    lines = ["digraph rosgraph {", "  rankdir=LR;"]
    for node in graph.nodes:
        lines.append(f"  {_dot_id('n:' + node.name)} [label={_dot_id(node.name)}, shape=ellipse];")
    for topic in graph.topics:
        label = _dot_id(f"{topic.name}\n{topic.type}").replace("\n", "\\n")
        lines.append(f"  {_dot_id('t:' + topic.name)} [label={label}, shape=box];")
    for topic in graph.topics:
        tid = _dot_id("t:" + topic.name)
        lines += [f"  {_dot_id('n:' + p)} -> {tid};" for p in topic.publishers]
        lines += [f"  {tid} -> {_dot_id('n:' + s)};" for s in topic.subscribers]
    lines.append("}")
    return "\n".join(lines)


@app.command("graph")
def graph_cmd(
    ctx: typer.Context,
    all_: Annotated[
        bool,
        typer.Option("-a", "--all", help="Include /rosout, /rosout_agg and the rosout node."),
    ] = False,
    fmt: Annotated[
        GraphFormat | None,
        typer.Option(
            "--format",
            "-F",
            help="text (a tree), json, yaml or dot (Graphviz).",
            show_default=False,
        ),
    ] = None,
) -> None:
    """Nodes and the topics between them, like rqt_graph, from the master's registrations."""
    from rostools.rosgraph.introspect import build_graph, system_state

    proxy = master(ctx, TOOL)
    graph = build_graph(system_state(proxy), proxy.topic_types(), include_debug=all_)
    chosen = fmt if fmt is not None else GraphFormat(settings(ctx).format.value)
    if chosen is GraphFormat.dot:
        sys.stdout.write(graph_dot(graph) + "\n")
    elif chosen is GraphFormat.text:
        if graph.nodes:
            sys.stdout.write(graph_text(graph) + "\n")
        else:
            _warn("no nodes are registered")
    else:
        emit(Format(chosen.value), graph.to_data())
