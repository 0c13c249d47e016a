"""ROS services as the bridge offers them: their schemas, and calls passed through as bytes.

The master names a service and its provider, not its type: the provider's TCPROS header
does (a probe, as ``rosservice type`` makes). A ROS 1 service header carries no definition,
so a service is advertised with its request and response schemas only when the type store
knows its type; the others are listed in a ``status`` message, once each.
"""

from __future__ import annotations

import asyncio
import logging
from dataclasses import dataclass

from rostools.errors import RostoolsError
from rostools.msgs.store import TypeStore
from rostools.msgs.topictype import ServiceType
from rostools.node.node import LiveNode
from rostools.node.service import ServiceClient
from rostools.web.channels import ENCODING, SCHEMA_ENCODING

log = logging.getLogger(__name__)

#: How long a client's service call may take before it fails (rosbridge waits as long).
CALL_TIMEOUT = 30.0
#: Seconds to read a provider's header for its type (``rosservice``'s probe: 5 s).
PROBE_TIMEOUT = 5.0
#: Providers probed at once, as a graph's services appear.
PROBES_AT_ONCE = 16


@dataclass
class Service:
    """A service as clients see it."""

    id: int
    name: str
    type: ServiceType
    request: str  # the request message's name
    response: str

    def advertisement(self, store: TypeStore) -> dict[str, object]:
        """The service in an ``advertiseServices`` message."""

        def schema(name: str) -> dict[str, str]:
            return {
                "encoding": ENCODING,
                "schemaName": name,
                "schemaEncoding": SCHEMA_ENCODING,
                "schema": store.full_text(name),
            }

        request, response = schema(self.request), schema(self.response)
        return {
            "id": self.id,
            "name": self.name,
            "type": self.type.type,
            "request": request,
            "response": response,
            # older clients (Studio 1.x) read these
            "requestSchema": request["schema"],
            "responseSchema": response["schema"],
        }


class Services:
    """Finds the types of a graph's services, and calls them."""

    def __init__(self, node: LiveNode, store: TypeStore) -> None:
        self.node = node
        self.store = store
        self._gate = asyncio.Semaphore(PROBES_AT_ONCE)

    async def describe(self, service_id: int, name: str) -> Service | str:
        """The service ``name``, or why it cannot be offered."""
        async with self._gate:
            try:
                header = await ServiceClient(self.node, name).probe(PROBE_TIMEOUT)
            except RostoolsError as err:
                return str(err)
        type_name = header.get("type", "")
        try:
            spec = self.store.srv(type_name)
            srv_type = ServiceType.of(self.store, type_name)
            self.store.full_text(spec.request.name)
            self.store.full_text(spec.response.name)
        except RostoolsError as err:
            return f"service {name} of type {type_name or '(none given)'}: {err}"
        if header.get("md5sum") not in (None, "*", srv_type.md5sum):
            return f"service {name}: its md5sum {header['md5sum']} is not that of {type_name} here"
        return Service(service_id, name, srv_type, spec.request.name, spec.response.name)

    async def call(self, service: Service, request: bytes) -> bytes:
        """Call ``service`` with the request's bytes; the response's bytes."""
        client = ServiceClient(self.node, service.name, service.type)
        return await client.call(request, CALL_TIMEOUT)
