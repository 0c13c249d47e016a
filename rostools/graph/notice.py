"""What a running node tells its user once, in one line: a peer it cannot reach, a restart.

A node hands each ``Notice`` to its ``notify`` callback. Commands print them on stderr; the
streaming commands also put them in their ``--format json`` stream as ``{"event": ...}``.
"""

from __future__ import annotations

import asyncio
import errno
import socket
import sys
from dataclasses import dataclass, field
from typing import Any

from rostools.network import is_loopback

#: A hint for a node whose address others cannot use.
SET_ADDRESS = "set ROS_IP or ROS_HOSTNAME on that host to an address others reach it at"


@dataclass(frozen=True)
class Notice:
    """One event: its kind (``peer_unreachable``, ``master_lost``, ...) and one line for people."""

    event: str
    message: str
    fields: dict[str, Any] = field(default_factory=dict)

    def as_json(self) -> dict[str, Any]:
        """The NDJSON event: ``{"event": ..., "message": ..., **fields}``."""
        return {"event": self.event, "message": self.message, **self.fields}


def to_stderr(notice: Notice) -> None:
    """The default ``notify``: one line on stderr."""
    sys.stderr.write(f"rostools: {notice.message}\n")
    sys.stderr.flush()


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
    if isinstance(err, (TimeoutError, asyncio.TimeoutError)):
        return Failure(f"{host} did not answer in time", "check the address and any firewall")
    if isinstance(err, OSError) and err.errno in (errno.EHOSTUNREACH, errno.ENETUNREACH):
        return Failure(f"no route to {host}", "check the address and the network")
    reason = (err.strerror if isinstance(err, OSError) else None) or str(err) or type(err).__name__
    return Failure(reason, SET_ADDRESS if loopback else "", False)
