"""``service list|uri|node|type`` without Typer (see ``rostools.cli.quick``)."""

from __future__ import annotations

import sys

from rostools.cli.output import Format, emit
from rostools.cli.settings import caller_id
from rostools.errors import NotFoundError, one_line
from rostools.names import make_global_ns, script_resolve

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from rostools.cli.settings import Settings
    from rostools.rosgraph.masterapi import MasterProxy
    from rostools.rosgraph.serviceclient import BlockingServiceClient


def client(proxy: MasterProxy, name: str, timeout: float | None) -> BlockingServiceClient:
    """A blocking client of service ``name``."""
    from rostools.rosgraph.serviceclient import BlockingServiceClient

    return BlockingServiceClient(proxy, name, timeout)


def services(proxy: MasterProxy) -> dict[str, list[str]]:
    """Every service and its nodes, sorted by name."""
    _, _, found = proxy.system_state()
    return {name: list(nodes) for name, nodes in sorted(found)}


def type_of(proxy: MasterProxy, name: str, timeout: float) -> tuple[str, str]:
    """(type, md5sum) of a service, from a probe of its server."""
    fields = client(proxy, name, timeout).probe(caller_id("rosservice"))
    return fields.get("type", ""), fields.get("md5sum", "")


def list_services(
    s: Settings, namespace: str | None, nodes: bool, fmt: Format | str | None
) -> None:
    """List services (rosservice list)."""
    found = services(s.master("rosservice"))
    if namespace:
        ns = script_resolve(namespace, "rosservice")
        found = {n: p for n, p in found.items() if n == ns or n.startswith(make_global_ns(ns))}
    out = s.output_format(fmt)
    if out is not Format.text:
        emit(out, [{"service": n, "nodes": p} for n, p in found.items()])
    elif nodes:
        sys.stdout.write("".join(one_line(f"{n} {','.join(p)}") + "\n" for n, p in found.items()))
    else:
        sys.stdout.write("".join(f"{one_line(n)}\n" for n in found))


def uri(s: Settings, service: str, fmt: Format | str | None) -> None:
    """The rosrpc URI of a service."""
    name = script_resolve(service, "rosservice")
    found = s.master("rosservice").lookup_service(name)
    emit(s.output_format(fmt), {"service": name, "uri": found}, lambda d: one_line(d["uri"]))


def node(s: Settings, service: str, fmt: Format | str | None) -> None:
    """The node that provides a service (rosservice node)."""
    name = script_resolve(service, "rosservice")
    providers = services(s.master("rosservice")).get(name)
    if not providers:
        raise NotFoundError(f"unknown service {name}")
    emit(
        s.output_format(fmt), {"service": name, "node": providers[0]}, lambda d: one_line(d["node"])
    )


def type_(s: Settings, service: str, timeout: float, fmt: Format | str | None) -> None:
    """A service's type, asked of its server (rosservice type)."""
    name = script_resolve(service, "rosservice")
    kind, md5 = type_of(s.master("rosservice"), name, timeout)
    data = {"service": name, "type": kind, "md5sum": md5}
    emit(s.output_format(fmt), data, lambda d: one_line(d["type"]))
