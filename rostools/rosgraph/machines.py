"""Which hosts the nodes run on, from their URIs (``rostools node machine``)."""

from __future__ import annotations

import socket
from collections.abc import Callable, Mapping
from urllib.parse import urlsplit

from rostools.errors import NotFoundError

#: The reason rosnode gives in ``shutdown`` calls (observed on the wire).


def host_of(uri: str) -> str | None:
    """The host name in a node URI."""
    return urlsplit(uri).hostname


def addresses(host: str) -> set[str]:
    """The addresses a host name resolves to (empty when it does not resolve)."""
    try:
        infos = socket.getaddrinfo(host, 0, 0, 0, socket.SOL_TCP)
    except (OSError, UnicodeError):
        return set()
    return {str(info[4][0]) for info in infos}


def machines(uris: Mapping[str, str | None]) -> dict[str, list[str]]:
    """Host -> sorted node names, from node -> URI (nodes without a URI are left out)."""
    hosts: dict[str, list[str]] = {}
    for node, uri in uris.items():
        host = host_of(uri) if uri else None
        if host:
            hosts.setdefault(host, []).append(node)
    return {h: sorted(ns) for h, ns in sorted(hosts.items())}


def nodes_on_machine(
    uris: Mapping[str, str | None],
    machine: str,
    resolve: Callable[[str], set[str]] = addresses,
) -> list[str]:
    """The nodes whose URI host is ``machine``, by name or by any address they share.

    NotFoundError when ``machine`` does not resolve to an address (as rosnode refuses).
    """
    wanted = resolve(machine)
    if not wanted:
        raise NotFoundError(f"cannot resolve machine name {machine} to an address")
    cache: dict[str, bool] = {}
    found = []
    for node, uri in uris.items():
        host = host_of(uri) if uri else None
        if not host:
            continue
        if host not in cache:
            cache[host] = host == machine or host in wanted or bool(resolve(host) & wanted)
        if cache[host]:
            found.append(node)
    return sorted(found)
