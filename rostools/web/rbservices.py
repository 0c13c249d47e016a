"""Services for rosbridge v2 clients: calls, and services a client serves to the graph.

A client calls ROS services and rosapi's; it serves one with ``advertise_service`` and
answers its calls with ``service_response``.
A call is answered by a ``service_response``: ``result`` true with the response's values, or
false with the reason as ``values`` (rosbridge's words where it has them: "Service /x does
not exist"). A ROS node's call to a client's service reaches the client as a
``call_service`` with the id ``service_request:NAME:N``; an answer that does not come within
``CALL_TIMEOUT``, or a client that leaves, fails the call, where rosbridge would wait forever.
"""

from __future__ import annotations

import asyncio
import json
from typing import TYPE_CHECKING, Any, Protocol

from rostools.errors import NotFoundError, RostoolsError, ServiceError
from rostools.msgs.codec import Codec
from rostools.msgs.codegen import element
from rostools.msgs.plain import to_rosbridge_json
from rostools.msgs.rosbridge import RosbridgeFiller
from rostools.msgs.topictype import ServiceType
from rostools.web.rbclient import RosbridgeClient, Served
from rostools.web.services import CALL_TIMEOUT, Service
from rostools.wire.rosbridge import ProtocolError, need

if TYPE_CHECKING:
    from rostools.web.state import BridgeState

#: Service calls one client may have in flight.
MAX_CALLS = 64


class RosApiLike(Protocol):
    """What answers rosapi's services (``rosapi.RosApi``)."""

    def handles(self, service: str) -> bool:
        """Whether ``service`` (with or without its leading slash) is one of rosapi's."""
        ...

    async def call(self, service: str, args: dict[str, Any]) -> dict[str, Any]:
        """The response's values; raises an error whose text is the failure's."""
        ...


class RbServices:
    """The service operations of rosbridge clients, for one bridge."""

    def __init__(self, bridge: BridgeState, rosapi: RosApiLike | None = None) -> None:
        self.bridge = bridge
        self.node = bridge.node
        self.rosapi = rosapi
        self.codec = Codec.of(bridge.store)
        #: service name -> (its provider's URI, its type), found by a probe
        self._types: dict[str, tuple[str, Service]] = {}
        self.served: dict[str, Served] = {}

    # calls -------------------------------------------------------------------------------

    async def op_call_service(self, client: RosbridgeClient, request: dict[str, Any]) -> None:
        """Call a service; the answer comes as a ``service_response`` with the call's id."""
        service = need(request, "service", str)
        ident = request.get("id")
        if ident is None and "#" in service:
            ident = service.split("#", 1)[1]  # rosbridge's "name#id" form
        name = service.split("#", 1)[0]
        args = request.get("args", [])
        if client.calls >= MAX_CALLS:
            self._answer(client, service, ident, None, f"more than {MAX_CALLS} calls in flight")
            raise ProtocolError(f"call_service: more than {MAX_CALLS} calls in flight")
        client.calls += 1
        self.bridge.spawn(self._call(client, service, name, args, ident))

    async def _call(
        self, client: RosbridgeClient, service: str, name: str, args: Any, ident: Any
    ) -> None:
        rosapi = self.rosapi if self.rosapi is not None and self.rosapi.handles(name) else None
        try:
            if self.bridge.opts.read_only and (
                rosapi is None or name.endswith(("set_param", "delete_param"))
            ):
                raise ServiceError("this bridge is read-only (--read-only)")
            if rosapi is not None:
                values = json.dumps(await rosapi.call(name, args if isinstance(args, dict) else {}))
            else:
                values = await self._ros_call(name, args)
        except (RostoolsError, ValueError) as err:
            self._answer(client, service, ident, None, str(err))
            client.tell("error", f"call_service {service}: {err}", ident)
        else:
            self._answer(client, service, ident, values, "")
        finally:
            client.calls -= 1

    async def _ros_call(self, name: str, args: Any) -> str:
        """Call a ROS service; the response in rosbridge's JSON."""
        name = self.node.resolve(name)
        try:
            uri = await self.node.master.lookup_service(name)
        except NotFoundError:
            raise ServiceError(f"Service {name} does not exist") from None
        known = self._types.get(name)
        if known is None or known[0] != uri:
            found = await self.bridge.describer.describe(0, name)
            if isinstance(found, str):
                raise ServiceError(found)
            known = self._types[name] = (uri, found)
        service = known[1]
        req = RosbridgeFiller(self.codec).message(service.request, args)
        raw = await self.bridge.describer.call(service, self.codec.serialize(req))
        response = self.codec.decode(service.response, raw)
        return to_rosbridge_json(self.codec, element(service.response))(response)

    def _answer(
        self, client: RosbridgeClient, service: str, ident: Any, values: str | None, why: str
    ) -> None:
        head = '{"op":"service_response","service":' + json.dumps(service) + ',"values":'
        tail = ',"result":true' if values is not None else ',"result":false'
        if ident is not None:
            tail += ',"id":' + json.dumps(ident)
        text = head + (values if values is not None else json.dumps(why)) + tail + "}"
        for part in client.cut(text):
            client.send(part)

    # services a client serves ------------------------------------------------------------

    async def op_advertise_service(self, client: RosbridgeClient, request: dict[str, Any]) -> None:
        """Serve ``service`` to the graph; its calls go to this client."""
        name = self.node.resolve(need(request, "service", str))
        type_name = need(request, "type", str)
        if self.bridge.opts.read_only:
            raise ProtocolError("advertise_service: this bridge is read-only (--read-only)")
        try:
            spec = self.bridge.store.srv(type_name)
            srv_type = ServiceType.of(self.bridge.store, type_name)
        except RostoolsError:
            raise ProtocolError(
                f"advertise_service: no service type {type_name} is known"
            ) from None
        old = self.served.get(name)
        if old is not None:
            client.tell(
                "warning", f"advertise_service: {name} was served already: it is this client's now"
            )
            await self._stop_serving(old)
        served = Served(name, client, spec.request.name, spec.response.name)
        self.served[name] = client.served[name] = served
        await self.node.advertise_service(name, srv_type, lambda req: self._serve(served, req))
        self.bridge.event("client_service", client=client.name, service=name, type=type_name)

    async def _serve(self, served: Served, request: bytes) -> bytes:
        rid = f"service_request:{served.name}:{next(served.counter)}"
        args = to_rosbridge_json(self.codec, element(served.request))(
            self.codec.decode(served.request, request)
        )
        answer = asyncio.get_running_loop().create_future()
        served.pending[rid] = answer
        served.client.send(
            '{"op":"call_service","id":' + json.dumps(rid) + ',"service":'
            + json.dumps(served.name) + ',"args":' + args + "}"
        )  # fmt: skip
        try:
            values = await asyncio.wait_for(answer, CALL_TIMEOUT)
        except TimeoutError:
            raise ServiceError(f"the web client did not answer in {CALL_TIMEOUT:g} s") from None
        finally:
            served.pending.pop(rid, None)
        try:
            return self.codec.serialize(
                RosbridgeFiller(self.codec).message(served.response, values)
            )
        except RostoolsError as err:
            served.client.tell("error", f"service_response {served.name}: {err}", rid)
            raise ServiceError(str(err)) from None

    async def op_service_response(self, client: RosbridgeClient, request: dict[str, Any]) -> None:
        """A client's answer to a call of a service it serves."""
        service = need(request, "service", str)
        result = need(request, "result", bool)
        ident = need(request, "id", str)
        values = request.get("values")
        served = client.served.get(self.node.resolve(service))
        if served is None:
            raise ProtocolError(f"Service {service} has not been advertised via rosbridge.")
        answer = served.pending.get(ident)
        if answer is None or answer.done():
            raise ProtocolError(f"service_response: no call {ident} of {service} is waiting")
        if result:
            answer.set_result(values if isinstance(values, dict | list) else {})
        else:
            answer.set_exception(ServiceError(str(values) if values is not None else "failed"))

    async def op_unadvertise_service(
        self, client: RosbridgeClient, request: dict[str, Any]
    ) -> None:
        """Stop serving ``service``."""
        name = self.node.resolve(need(request, "service", str))
        served = client.served.get(name)
        if served is None:
            raise ProtocolError(
                f"Service {name} has not been advertised via rosbridge, can't unadvertise."
            )
        await self._stop_serving(served)

    async def _stop_serving(self, served: Served) -> None:
        served.client.served.pop(served.name, None)
        if self.served.get(served.name) is served:
            del self.served[served.name]
            try:
                await self.node.unadvertise_service(served.name)
            except RostoolsError as err:
                self.bridge.event("warning", message=f"unadvertising {served.name}: {err}")
        for answer in served.pending.values():
            if not answer.done():
                answer.set_exception(ServiceError(f"{served.name} is no longer served"))

    async def forget_client(self, client: RosbridgeClient) -> None:
        """The services of a client that left."""
        for served in list(client.served.values()):
            await self._stop_serving(served)
