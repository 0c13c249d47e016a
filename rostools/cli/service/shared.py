"""What the service commands share, without Typer: the master's services, a server's type."""

from __future__ import annotations

from rostools.cli.settings import caller_id
from rostools.errors import NotFoundError

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from rostools.msgs.spec import SrvSpec
    from rostools.msgs.store import TypeStore
    from rostools.rosgraph.masterapi import MasterProxy
    from rostools.rosgraph.serviceclient import BlockingServiceClient

TOOL = "rosservice"


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
    fields = client(proxy, name, timeout).probe(caller_id(TOOL))
    return fields.get("type", ""), fields.get("md5sum", "")


def service_spec(store: TypeStore, type_name: str, name: str) -> SrvSpec:
    """The definition of service ``name``'s type, or a NotFoundError that says how to add it."""
    try:
        return store.srv(type_name)
    except NotFoundError:
        raise NotFoundError(
            f"{name} is a {type_name}, a service type not installed here",
            hint="add its package with --msg-path",
        ) from None
