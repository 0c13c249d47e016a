"""What a node's parts ask of the node they belong to.

Publishers, subscribers and service servers and clients talk to their node through
``Owner``, and the node's watch on the master through ``watch.Registrations``; ``Node``
implements both. The parts import these Protocols, never ``node.py``, so the imports of this
package run one way: the node imports its parts.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Protocol

from rostools.node.notice import Notice

if TYPE_CHECKING:
    from rostools.node.mastercalls import LiveMaster


class Owner(Protocol):
    """A node as its publishers, subscribers and services see it."""

    #: The node's resolved name (its caller id).
    name: str
    master_uri: str
    #: The address it gives out, and the port of its TCPROS server.
    host: str
    tcpros_port: int
    #: True while the master does not answer (notices wait until it is back).
    master_lost: bool
    #: Where the node's one-line notices go.
    notify: Callable[[Notice], None]

    @property
    def uri(self) -> str:
        """Its slave API's XML-RPC URI."""
        ...

    def next_connection_id(self) -> int:
        """A number for a new connection, unique in this node (``getBusInfo``)."""
        ...

    #: The master, typed (``node.mastercalls.LiveMaster``).
    master: LiveMaster
