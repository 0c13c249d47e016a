"""``rostools service list|uri|node|type|args|info|find``: what the master and servers say.

Typer-free (``rostools.cli.declare``): the launcher runs the quick ones without Typer.
"""

from __future__ import annotations

from rostools.cli import output
from rostools.cli.declare import command
from rostools.cli.output import Format, emit, lines
from rostools.cli.service.shared import TOOL, service_spec, services, type_of
from rostools.errors import NotFoundError, one_line
from rostools.names import make_global_ns, script_resolve
from rostools.rosgraph.masterapi import PROBE_TIMEOUT

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from typing import Annotated

    import typer

    from rostools.cli.common import FormatOpt, MsgPathOpt
    from rostools.cli.service.options import ServiceArg, TimeoutOpt
    from rostools.cli.settings import Settings


@command("list", quick=True)
def list_services(
    s: Settings,
    namespace: Annotated[
        str | None, typer.Argument(help="Only services under this namespace.")
    ] = None,
    nodes: Annotated[
        bool, typer.Option("--nodes", "-n", help="Show the node of each service.")
    ] = False,
    fmt: FormatOpt = None,
) -> None:
    """List services (rosservice list)."""
    found = services(s.master(TOOL))
    if namespace:
        ns = script_resolve(namespace, TOOL)
        found = {n: p for n, p in found.items() if n == ns or n.startswith(make_global_ns(ns))}
    out = s.output_format(fmt)
    if out is not Format.text:
        emit(out, [{"service": n, "nodes": p} for n, p in found.items()])
    elif nodes:
        output.put("".join(one_line(f"{n} {','.join(p)}") + "\n" for n, p in found.items()))
    else:
        output.put("".join(f"{one_line(n)}\n" for n in found))


@command(quick=True)
def uri(s: Settings, service: ServiceArg, fmt: FormatOpt = None) -> None:
    """The rosrpc URI of a service."""
    name = script_resolve(service, TOOL)
    found = s.master(TOOL).lookup_service(name)
    emit(s.output_format(fmt), {"service": name, "uri": found}, lambda d: one_line(d["uri"]))


@command(quick=True)
def node(s: Settings, service: ServiceArg, fmt: FormatOpt = None) -> None:
    """The node that provides a service (rosservice node)."""
    name = script_resolve(service, TOOL)
    providers = services(s.master(TOOL)).get(name)
    if not providers:
        raise NotFoundError(f"unknown service {name}")
    emit(
        s.output_format(fmt), {"service": name, "node": providers[0]}, lambda d: one_line(d["node"])
    )


@command("type", quick=True)
def type_(
    s: Settings, service: ServiceArg, timeout: TimeoutOpt = PROBE_TIMEOUT, fmt: FormatOpt = None
) -> None:
    """A service's type, asked of its server (rosservice type)."""
    name = script_resolve(service, TOOL)
    kind, md5 = type_of(s.master(TOOL), name, timeout)
    data = {"service": name, "type": kind, "md5sum": md5}
    emit(s.output_format(fmt), data, lambda d: one_line(d["type"]))


@command()
def args(
    s: Settings,
    service: ServiceArg,
    timeout: TimeoutOpt = PROBE_TIMEOUT,
    fmt: FormatOpt = None,
    msg_path: MsgPathOpt = None,
) -> None:
    """The request fields of a service (rosservice args)."""
    from rostools.cli.settings import type_store

    name = script_resolve(service, TOOL)
    kind, _ = type_of(s.master(TOOL), name, timeout)
    fields = [f.name for f in service_spec(type_store(msg_path), kind, name).request.fields]
    emit(s.output_format(fmt), fields, " ".join)


@command()
def info(
    s: Settings,
    service: ServiceArg,
    timeout: TimeoutOpt = PROBE_TIMEOUT,
    fmt: FormatOpt = None,
    msg_path: MsgPathOpt = None,
) -> None:
    """Node, URI, type and request fields of a service (rosservice info)."""
    from rostools.cli.settings import type_store

    name = script_resolve(service, TOOL)
    proxy = s.master(TOOL)
    providers = services(proxy).get(name)
    if not providers:
        raise NotFoundError(f"unknown service {name}")
    found_uri = proxy.lookup_service(name)
    kind, md5 = type_of(proxy, name, timeout)
    try:
        request: list[str] | None = [f.name for f in type_store(msg_path).srv(kind).request.fields]
    except NotFoundError:  # a type not installed here: the rest is still worth showing
        request = None
    data = {
        "service": name,
        "node": providers[0],
        "uri": found_uri,
        "type": kind,
        "md5sum": md5,
        "args": request,
    }
    shown = [f"Node: {providers[0]}", f"URI: {found_uri}", f"Type: {kind}"]
    shown.append(f"Args: {' '.join(request or [])}")
    emit(s.output_format(fmt), data, lambda _: lines(shown))


@command()
def find(
    s: Settings,
    srv_type: Annotated[str, typer.Argument(help="A service type, pkg/Type.")],
    timeout: TimeoutOpt = 2.0,
    fmt: FormatOpt = None,
) -> None:
    """Services of a given type, found by probing each (rosservice find)."""
    from rostools.errors import RostoolsError

    proxy = s.master(TOOL)
    found = []
    for name in services(proxy):
        try:
            if type_of(proxy, name, timeout)[0] == srv_type:
                found.append(name)
        except RostoolsError:
            continue  # a dead or slow server is simply not a match
    emit(s.output_format(fmt), found, lines)
