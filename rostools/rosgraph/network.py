"""Which name a node gives out and which address it binds: rosgraph's network rules.

rospy decides both in ``rosgraph.network`` (``get_address_override``, ``get_host_name``,
``get_bind_address``), and roscpp the same way in ``network.cpp``; every node rostools starts
follows them, so it is reachable exactly where a rospy node in its place would be:

- the name given out is the first of ``__hostname:=``/``__ip:=``, ``ROS_HOSTNAME``,
  ``ROS_IP``; else the machine's host name; else, when that is ``localhost`` or ``127.*``, the
  first interface address that is not loopback;
- the node binds that name's address when it is a loopback one, else every interface.

Only the standard library, as ``names``.
"""

from __future__ import annotations

import errno
import ipaddress
import os
import socket
import struct
from collections.abc import Mapping
from dataclasses import dataclass
from urllib.parse import urlsplit

from rostools.errors import UsageError

#: Bind on every interface (rosgraph's ``get_bind_address`` without an override).
ANY_ADDRESS = "0.0.0.0"  # noqa: S104 - others must reach a node that gives out a public name
#: Linux's ioctl for an interface's IPv4 address (``<linux/sockios.h>``).
_SIOCGIFADDR = 0x8915


def is_loopback(name: str) -> bool:
    """Whether ``name`` is ``localhost`` or a loopback address (127/8, ::1)."""
    if name == "localhost":
        return True
    try:
        return ipaddress.ip_address(name).is_loopback
    except ValueError:
        return False


def address_override(
    env: Mapping[str, str] | None = None, remappings: Mapping[str, str] | None = None
) -> str | None:
    """``__hostname:=``/``__ip:=``, then ``ROS_HOSTNAME``, then ``ROS_IP``; None if none is set.

    An empty variable counts as unset. A scheme or a port in one is refused: rospy warns and
    gives out a URI nobody can reach; we say so and stop.
    """
    env = os.environ if env is None else env
    remappings = remappings or {}
    for key, source in (
        ("__hostname", remappings),
        ("__ip", remappings),
        ("ROS_HOSTNAME", env),
        ("ROS_IP", env),
    ):
        value = source.get(key, "")
        if value:
            _check_override(key, value)
            return value
    return None


def _check_override(key: str, value: str) -> None:
    if "://" in value:
        raise UsageError(f"{key}={value} is not a host: leave out the protocol")
    try:
        ipaddress.ip_address(value)
        return  # an IPv6 address has colons, and no port
    except ValueError:
        pass
    if ":" in value or not value.strip() or any(c.isspace() for c in value):
        raise UsageError(f"{key}={value!r} is not a host name or address (no port, no spaces)")


def local_addresses() -> list[str]:
    """The IPv4 addresses of this machine's interfaces, loopback included, in order."""
    found: list[str] = []
    try:
        import fcntl

        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
            for _, name in socket.if_nameindex():
                request = struct.pack("256s", name.encode()[:15])
                try:
                    answer = fcntl.ioctl(sock.fileno(), _SIOCGIFADDR, request)
                except OSError:
                    continue  # an interface without an IPv4 address
                found.append(socket.inet_ntoa(answer[20:24]))
    except (ImportError, OSError):
        pass
    if found:
        return found
    try:  # not Linux: as rosgraph's cross-platform branch, what the host name resolves to
        infos = socket.getaddrinfo(socket.gethostname(), 0, socket.AF_INET, socket.SOCK_STREAM)
    except OSError:
        return []
    return list(dict.fromkeys(str(info[4][0]) for info in infos))


def local_address() -> str:
    """The first interface address that is not loopback (rosgraph's ``get_local_address``)."""
    addresses = local_addresses()
    if len(addresses) == 1:
        return addresses[0]
    return next((a for a in addresses if not is_loopback(a)), "127.0.0.1")


def host_name(
    env: Mapping[str, str] | None = None, remappings: Mapping[str, str] | None = None
) -> str:
    """The name a node gives out in its URIs (rosgraph's ``get_host_name``)."""
    override = address_override(env, remappings)
    if override:
        return override
    try:
        name = socket.gethostname()
    except OSError:
        name = ""
    if not name or is_loopback(name) or name.startswith("127."):
        return local_address()
    return name


def bind_address(name: str) -> str:
    """Where a node that gives out ``name`` listens: there if loopback, else everywhere."""
    if name == "localhost":
        return "127.0.0.1"
    return name if is_loopback(name) else ANY_ADDRESS


def uri_host(uri: str) -> str:
    """The host part of an ``http://host:port/`` URI (``localhost`` when there is none)."""
    return urlsplit(uri).hostname or "localhost"


#: A hint for a node whose address others cannot use.
SET_ADDRESS = "set ROS_IP or ROS_HOSTNAME on that host to an address others reach it at"


@dataclass(frozen=True)
class Failure:
    """Why a peer could not be reached, and whether retrying could soon change that."""

    reason: str
    hint: str = ""
    #: False for what may clear up in a moment (a refused connection while a node exits).
    lasting: bool = True
    #: We connected, then dropped the connection (bad data), rather than failing to connect.
    dropped: bool = False


def explain(err: BaseException, host: str, peer: bool = True) -> Failure:
    """A connection error to ``host`` as a reason and a hint a user can act on.

    A ``peer`` (a node, not the master) that gives out a loopback address is named as such:
    only its own host can reach it there.
    """
    if isinstance(err, socket.gaierror):
        return Failure(f"{host} does not resolve here", SET_ADDRESS)
    loopback = peer and is_loopback(host)
    if isinstance(err, ConnectionRefusedError):
        if loopback:
            return Failure(f"connection refused at {host}, a loopback address", SET_ADDRESS, False)
        return Failure(
            "connection refused",
            "the node may have died without unregistering ('rostools node cleanup' purges it)",
            False,
        )
    if isinstance(err, TimeoutError) or type(err).__name__ == "TimeoutError":  # 3.10's asyncio's
        return Failure(f"{host} did not answer in time", "check the address and any firewall")
    if isinstance(err, OSError) and err.errno in (errno.EHOSTUNREACH, errno.ENETUNREACH):
        return Failure(f"no route to {host}", "check the address and the network")
    if not isinstance(err, OSError):
        # it was reached and answered: what it said is wrong, not where it is
        return Failure(f"it does not speak the ROS XML-RPC API ({err or type(err).__name__})")
    reason = err.strerror or str(err) or type(err).__name__
    return Failure(reason, SET_ADDRESS if loopback else "", False)
