"""rosapi's services, answered by the bridge itself as rosapi_node 0.11.17 answers them.

roslib's helpers (``getTopics``, ``getMessageDetails``, ``Param``) call ``/rosapi/*``
services, which rosbridge_suite serves from a separate node, ``rosapi_node``. ``RosApi``
answers the same 25 services from our own node: ``call`` for a rosbridge client's
``call_service`` (the name with or without its leading slash: roslib 2.x sends both), and
``advertise`` to serve them as ROS services of rosapi's own types (``rosapi/Topics``...), so
that a rospy client gets the same answer as from rosapi_node.

The answers follow rosapi's Python and the ROS 1 tools it calls (rostopic, rosservice,
rosnode, rospy's parameter calls), quirks included: names are compared as given (only the
master resolves them, relative to the root namespace where rosapi_node runs), a service's
type is read from its server's header, parameters travel as JSON text, and
``message_details`` lays out typedefs depth first, with ``time`` and ``duration`` as their
own typedefs. rosapi_node's ``~topics_glob`` filters are not offered: everything is public.

Not to be confused with ``rostools/wire/rosapi.py``, which checks the arguments of ROS's own
XML-RPC APIs (the Master and Slave APIs), not rosbridge's rosapi.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import os
from collections.abc import Awaitable, Callable
from typing import TYPE_CHECKING, Any, Literal

from rostools.errors import NotFoundError, RostoolsError, TimeoutExpired, UnreachableError
from rostools.msgs.codec import Codec
from rostools.msgs.rosbridge import RosbridgeFiller
from rostools.msgs.spec import MsgSpec
from rostools.msgs.store import TypeStore
from rostools.msgs.topictype import ServiceType
from rostools.node.clock import RosClock
from rostools.node.mastercalls import LiveMaster
from rostools.node.service import ServiceClient
from rostools.rosgraph.masterapi import MasterError

if TYPE_CHECKING:
    from rostools.node.node import LiveNode

#: The types rosapi gives no typedef of (``objectutils.atomics``); ``char`` is not one.
ATOMICS = frozenset(
    ("bool", "byte", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64",
     "uint64", "float32", "float64", "string")
)  # fmt: skip
SPECIALS = ("time", "duration")
#: What genpy puts in a new message's field, as ``str`` writes it (rosapi's ``examples``).
_DEFAULTS = {"bool": "False", "float32": "0.0", "float64": "0.0", "string": ""}
#: rosapi_node's name: rospy resolves ``~name`` parameters under it.
NODE_NAME = "/rosapi"
#: What rosservice says of a master out of reach (rosapi and rosbridge pass it on).
MASTER_GONE = "Unable to communicate with master!"
#: How long a service's header is waited for (rosservice's probe: 5 s). Twice that here: the
#: probes of a listing run at once, and a loaded machine's rospy server took over 5 s to
#: answer one of thirty (a dead provider costs the wait once a call, as rosservice's does).
PROBE_TIMEOUT = 10.0

Handler = Callable[["RosApi", Any], Awaitable[dict[str, Any]]]


class RosApiFailure(RostoolsError):  # noqa: N818 - the name the bridge's callers know
    """A call that failed; its text is what rosbridge answers (``result: false``).

    ``reason`` is rosapi's own words, which a ROS client of ``advertise``'s services gets
    after "error processing request: ", as rospy sends them.
    """

    def __init__(self, text: str, reason: str | None = None) -> None:
        super().__init__(text)
        self.reason = text if reason is None else reason


class _HandlerError(Exception):
    """rosapi's handler raised: its words, wrapped by ``RosApi.call`` as rosbridge shows them."""


class _MasterGoneError(_HandlerError):
    """The master is out of reach: rosbridge fails the call before it reaches rosapi."""

    def __init__(self) -> None:
        super().__init__(MASTER_GONE)


class RosApi:
    """rosapi_node's services, answered from ``node``'s view of the graph."""

    def __init__(self, node: LiveNode, store: TypeStore) -> None:
        self.node = node
        self.store = store
        self.codec = Codec.of(store)
        self.filler = RosbridgeFiller(self.codec)
        #: type -> full definition, as publishers' headers gave it (``learn``)
        self.learnt: dict[str, str] = {}
        self._types = store
        self._clock: RosClock | None = None
        self._advertised: list[str] = []

    # the services ---------------------------------------------------------------------

    @staticmethod
    def _short(service: str) -> str | None:
        name = service[1:] if service.startswith("/") else service
        head, _, short = name.partition("/")
        return short if head == "rosapi" and short in SERVICES else None

    def handles(self, service: str) -> bool:
        """Whether ``service`` ("/rosapi/topics" or "rosapi/topics") is one of rosapi's."""
        return self._short(service) is not None

    async def call(self, service: str, args: dict[str, Any]) -> dict[str, Any]:
        """The response's values, in rosapi's field order; ``RosApiFailure`` as rosbridge's."""
        short = self._short(service)
        if short is None:
            raise RosApiFailure(f"Service {service} does not exist")
        srv_type, handler = SERVICES[short]
        spec = self.store.srv(srv_type)
        try:
            request = self.filler.message(spec.request.name, args)
        except RostoolsError as err:  # rosbridge's words for values that do not fit
            raise RosApiFailure(str(err)) from None
        try:
            return await handler(self, request)
        except _MasterGoneError:
            # rosbridge asks the master for the service's type first, and fails there
            raise RosApiFailure(MASTER_GONE) from None
        except _HandlerError as err:
            reason = str(err)
            raw = f"error processing request: {reason}".encode()
            # rospy's ServiceException puts the error's bytes in as Python writes them
            text = f"service [/rosapi/{short}] responded with an error: {raw!r}"
            raise RosApiFailure(text, reason) from None

    def learn(self, type_name: str, definition: str) -> None:
        """A type as a publisher's header defined it (``message_definition``).

        Its details are given where the store does not hold it.
        """
        if not definition or self.learnt.get(type_name) == definition:
            return
        self.learnt[type_name] = definition
        self._types = self._types.with_definition(type_name, definition)

    # as ROS services --------------------------------------------------------------------

    async def advertise(self) -> None:
        """Serve every ``/rosapi/NAME`` to the graph, in rosapi's own service types."""
        for short, (srv_type, _) in SERVICES.items():
            name = f"/rosapi/{short}"
            await self.node.advertise_service(
                name, ServiceType.of(self.store, srv_type), self._serving(short, srv_type)
            )
            self._advertised.append(name)

    async def unadvertise(self) -> None:
        """Stop serving what ``advertise`` served."""
        while self._advertised:
            await self.node.unadvertise_service(self._advertised.pop())

    def _serving(self, short: str, srv_type: str) -> Callable[[bytes], Awaitable[bytes]]:
        spec = self.store.srv(srv_type)
        handler = SERVICES[short][1]
        request_name, response_name = spec.request.name, spec.response.name

        async def serve(raw: bytes) -> bytes:
            request = self.codec.decode(request_name, raw)
            try:
                values = await handler(self, request)
            except _HandlerError as err:
                # a plain error: the client reads "error processing request: ...", as rospy's
                raise RostoolsError(str(err)) from None
            return self.codec.serialize(self.filler.message(response_name, values))

        return serve

    # the graph --------------------------------------------------------------------------

    async def _master(self, method: str, *args: Any) -> Any:
        """A master call; a master out of reach fails as rosservice says it."""
        try:
            return await self.node.master.call(method, *args)
        except (UnreachableError, TimeoutExpired) as err:
            raise _MasterGoneError from err

    async def _state(self) -> tuple[list[Any], list[Any], list[Any]]:
        pubs, subs, srvs = await self._master("getSystemState")
        return pubs, subs, srvs

    async def _topics_and_types(self) -> tuple[list[str], list[str]]:
        """rosapi's ``get_topics_and_types``: topics with a publisher or a subscriber.

        They come in ``getTopicTypes`` order, those of no known type last with "";
        nothing when the master fails.
        """
        try:
            pubs, subs, _ = await self._state()
            types = await self._master("getTopicTypes")
        except RostoolsError:  # a master that answers, with a failure
            return [], []
        live = {t for t, _ in pubs} | {t for t, _ in subs}
        pairs = [(str(t), str(ty)) for t, ty in types if t in live]
        typed = {t for t, _ in pairs}
        pairs += [(t, "") for t in sorted(live - typed)]
        return [t for t, _ in pairs], [ty for _, ty in pairs]

    async def _service_type(self, name: str) -> str | None:
        """rosservice's ``get_service_type``: the type in the server's header.

        The server is asked by the name as given: the master resolves it, and the server
        compares it with its own.
        """
        try:
            fields = await ServiceClient(self.node, name).probe(PROBE_TIMEOUT)
        except (RostoolsError, OSError):
            return None
        return fields.get("type")

    # typedefs ---------------------------------------------------------------------------

    def _spec(
        self, kind: Literal["msg", "srv"], type_name: str
    ) -> MsgSpec | tuple[MsgSpec, MsgSpec]:
        """A type as ros_loader loads it, failing with ros_loader's words."""
        parts = [p for p in type_name.split("/") if p]
        if len(parts) != 2:
            raise _HandlerError(f"{type_name} is not a valid type string")
        package, short = parts
        known = self._types.packages("msg") + self._types.packages("srv")
        if package not in known:
            paths = [p for p in os.environ.get("ROS_PACKAGE_PATH", "").split(os.pathsep) if p]
            where = "".join(f"\nROS path [{i}]={p}" for i, p in enumerate(paths))
            raise _HandlerError(
                f"Unable to load the manifest for package {package}. Caused by: {package}{where}"
            )
        full = f"{package}/{short}"
        try:
            if kind == "srv":
                srv = self._types.srv(full)
                return srv.request, srv.response
            return self._types.msg(full)
        except RostoolsError:
            if package not in self._types.packages(kind):
                raise _HandlerError(
                    f"Unable to import {package}.{kind} from package {package}. Caused by: "
                    f"No module named '{package}.{kind}'"
                ) from None
            raise _HandlerError(
                f"Unable to import {kind} class {short} from package {package}. Caused by "
                f"module '{package}.{kind}' has no attribute '{short}'"
            ) from None

    def _typedef(self, spec: MsgSpec, type_name: str) -> dict[str, Any]:
        """rosapi's ``_get_typedef`` of a message of ``spec``, named ``type_name``."""
        names, types, lengths, examples = [], [], [], []
        for f in spec.fields:
            names.append(f.name)
            length = -1 if not f.is_array else (0 if f.length is None else f.length)
            lengths.append(length)
            if f.base in ATOMICS or f.base in SPECIALS:
                types.append(f.base)
            elif f.base == "char":
                # genpy's char is an int (an array of them, bytes): rosapi asks it its module
                held = "bytes" if f.is_array else "int"
                raise _HandlerError(f"'{held}' object has no attribute '__module__'")
            else:
                types.append(f.base)
            if length >= 0:
                examples.append("[]")
            elif f.base not in ATOMICS:
                examples.append("{}")
            else:
                examples.append(_DEFAULTS.get(f.base, "0"))
        constants = sorted(spec.constants, key=lambda c: c.name)
        return {
            "type": type_name,
            "fieldnames": names,
            "fieldtypes": types,
            "fieldarraylen": lengths,
            "examples": examples,
            "constnames": [c.name for c in constants],
            "constvalues": [str(c.value) for c in constants],
        }

    def _typedefs(self, type_name: str, seen: list[str]) -> list[dict[str, Any]]:
        """rosapi's ``_get_typedefs_recursive``: this type's and its fields', depth first."""
        if type_name in seen:
            return []
        seen.append(type_name)
        if type_name in ATOMICS:
            return []
        if type_name in SPECIALS:
            return [{
                "type": type_name, "fieldnames": ["secs", "nsecs"],
                "fieldtypes": ["int32", "int32"], "fieldarraylen": [-1, -1],
                "examples": ["0", "0"], "constnames": [], "constvalues": [],
            }]  # fmt: skip
        spec = self._spec("msg", type_name)
        assert isinstance(spec, MsgSpec)
        return self._nested(self._typedef(spec, spec.name), seen)

    def _nested(self, typedef: dict[str, Any], seen: list[str]) -> list[dict[str, Any]]:
        out = [typedef]
        for field_type in typedef["fieldtypes"]:
            out += self._typedefs(field_type, seen)
        return out

    def _service_typedefs(self, type_name: str, part: int) -> list[dict[str, Any]]:
        specs = self._spec("srv", type_name)
        assert isinstance(specs, tuple)
        spec = specs[part]
        return self._nested(self._typedef(spec, spec.name), [])

    def _full_text(self, type_name: str) -> str:
        """rosapi's ``get_typedef_full_text``: the type's whole definition, or ""."""
        if type_name in self.learnt:
            return self.learnt[type_name]
        try:
            return self.store.full_text(type_name)
        except RostoolsError:
            return ""

    # parameters ---------------------------------------------------------------------------

    @staticmethod
    def _param_name(name: str) -> str:
        """A parameter name as rospy resolves it in rosapi_node (in the root namespace)."""
        if name.startswith("~"):
            return f"{NODE_NAME}/{name[1:]}"
        return name if name.startswith("/") else "/" + name

    async def _get_param(self, name: str) -> tuple[bool, Any]:
        try:
            return True, await self._master("getParam", self._param_name(name))
        except RostoolsError:  # unset, or a name the master refuses: rospy's KeyError
            return False, None

    async def _has_param(self, name: str) -> bool:
        try:
            return bool(await self._master("hasParam", self._param_name(name)))
        except RostoolsError:
            return False

    async def _now(self) -> int:
        if self._clock is None:
            self._clock = RosClock()
            await self._clock.start(self.node)
        return self._clock.now()


# the handlers, one per service, each as rosapi_node's ------------------------------------


async def _topics(api: RosApi, _: Any) -> dict[str, Any]:
    topics, types = await api._topics_and_types()
    return {"topics": topics, "types": types}


async def _topics_for_type(api: RosApi, req: Any) -> dict[str, Any]:
    types = await api._master("getTopicTypes")
    return {"topics": [str(t) for t, ty in types if ty == req.type]}


async def _topics_and_raw_types(api: RosApi, _: Any) -> dict[str, Any]:
    topics, types = await api._topics_and_types()
    texts = [api._full_text(t) for t in types]
    return {"topics": topics, "types": types, "typedefs_full_text": texts}


async def _services(api: RosApi, _: Any) -> dict[str, Any]:
    _, _, srvs = await api._state()
    return {"services": [str(s) for s, _ in srvs]}


async def _services_for_type(api: RosApi, req: Any) -> dict[str, Any]:
    _, _, srvs = await api._state()
    names = [str(s) for s, _ in srvs]
    found = await asyncio.gather(*(api._service_type(s) for s in names))
    return {"services": [s for s, t in zip(names, found, strict=True) if t == req.type]}


async def _service_type(api: RosApi, req: Any) -> dict[str, Any]:
    return {"type": await api._service_type(req.service) or ""}


async def _service_providers(api: RosApi, req: Any) -> dict[str, Any]:
    _, _, srvs = await api._state()
    found = await asyncio.gather(*(api._service_type(str(s)) for s, _ in srvs))
    providers: list[str] = []
    for (_, nodes), found_type in zip(srvs, found, strict=True):
        if (found_type or "") == req.service:  # rosapi's request names the type "service"
            providers += [str(n) for n in nodes]
    return {"providers": providers}


async def _service_node(api: RosApi, req: Any) -> dict[str, Any]:
    _, _, srvs = await api._state()
    for name, nodes in srvs:
        if name == req.service:
            return {"node": str(nodes[0]) if nodes else ""}
    return {"node": ""}


async def _service_host(api: RosApi, req: Any) -> dict[str, Any]:
    name = req.service if req.service.startswith(("/", "~")) else "/" + req.service
    try:
        uri = str(await api._master("lookupService", name))
    except (NotFoundError, MasterError):
        return {"host": ""}
    rest = uri[9:]  # past "rosrpc://", as rosapi cuts it
    return {"host": rest[: rest.find(":")]}


async def _nodes(api: RosApi, _: Any) -> dict[str, Any]:
    nodes = {str(n) for part in await api._state() for _, names in part for n in names}
    return {"nodes": sorted(nodes)}


async def _node_details(api: RosApi, req: Any) -> dict[str, Any]:
    pubs, subs, srvs = await api._state()

    def of(entries: list[Any]) -> list[str]:
        return sorted(str(name) for name, nodes in entries if req.node in nodes)

    return {"subscribing": of(subs), "publishing": of(pubs), "services": of(srvs)}


async def _action_servers(api: RosApi, _: Any) -> dict[str, Any]:
    topics, _ = await api._topics_and_types()
    return {"action_servers": action_servers(topics)}


def action_servers(topics: list[str]) -> list[str]:
    """rosapi's ``filter_action_servers``: namespaces with all five action topics.

    They are counted as rosapi counts them: a namespace is listed again for each topic that
    follows its fifth, until another namespace starts.
    """
    kinds = ["cancel", "feedback", "goal", "result", "status"]
    found: list[str] = []
    current, seen = "", [0] * 5
    for topic in sorted(topics):
        parts = topic.split("/")
        if len(parts) >= 3:
            last, namespace = parts[-1], "/".join(parts[:-1])
            if current != namespace:
                current, seen = namespace, [0] * 5
            if last in kinds:
                seen[kinds.index(last)] = 1
        if all(seen):
            found.append(current)
    return found


async def _topic_type(api: RosApi, req: Any) -> dict[str, Any]:
    types = [(str(t), str(ty)) for t, ty in await api._master("getTopicTypes")]
    return {"type": topic_type(api._types, types, req.topic)}


def topic_type(store: TypeStore, types: list[tuple[str, str]], topic: str) -> str:
    """rostopic's ``get_topic_type`` of ``topic``, which may name a field (/odom/pose).

    That is the exact topic, else the longest topic it lies under whose type has that field.
    """
    matches = [(t, ty) for t, ty in types if t == topic]
    if not matches:
        under = sorted(((t, ty) for t, ty in types if topic.startswith(t + "/")), reverse=True)
        while under:
            t, ty = under[0]
            path = topic[len(t) + 1 :].rstrip("/").split("[")[0]
            if path == "" or not store.has_msg(ty):
                break
            if not _has_field(store, ty, path):
                under.pop(0)
                continue
            under = [(t, ty)]
            break
        matches = under
    if not matches or matches[0][1] == "*":
        return ""
    return matches[0][1]


def _has_field(store: TypeStore, type_name: str, path: str) -> bool:
    """Whether genpy's message of ``type_name`` has the attribute path ``a/b/c``."""
    spec: MsgSpec | None = store.msg(type_name)
    for part in path.split("/"):
        if spec is None:  # a value with no attributes (a string, a list)
            return False
        if part in ("secs", "nsecs") and spec.name in SPECIALS:
            spec = None
            continue
        f = next((f for f in spec.fields if f.name == part), None)
        if f is None:
            return False
        if f.is_array or f.base in ATOMICS:
            spec = None
        elif f.base in SPECIALS:
            spec = MsgSpec(f.base, (), (), "")
        else:
            spec = store.msg(f.base)
    return True


async def _publishers(api: RosApi, req: Any) -> dict[str, Any]:
    pubs, _, _ = await api._state()
    return {"publishers": [str(n) for n in dict(pubs).get(req.topic, [])]}


async def _subscribers(api: RosApi, req: Any) -> dict[str, Any]:
    _, subs, _ = await api._state()
    return {"subscribers": [str(n) for n in dict(subs).get(req.topic, [])]}


async def _get_param(api: RosApi, req: Any) -> dict[str, Any]:
    default: Any = None
    if req.default != "":
        try:
            default = json.loads(req.default)
        except ValueError:
            default = req.default
    found, value = await api._get_param(req.name)
    return {"value": json.dumps(value if found else default)}


async def _set_param(api: RosApi, req: Any) -> dict[str, Any]:
    try:
        value = json.loads(req.value)
    except ValueError:
        raise _HandlerError(
            "Due to the type flexibility of the ROS parameter server, the value argument to "
            "set_param must be a JSON-formatted string."
        ) from None
    if value is None or _holds_none(value):  # XML-RPC has no nil (Python's marshaller's words)
        raise _HandlerError("cannot marshal None unless allow_none is enabled")
    await api._master("setParam", api._param_name(req.name), value)
    return {}


def _holds_none(value: Any) -> bool:
    if isinstance(value, dict):
        return any(v is None or _holds_none(v) for v in value.values())
    if isinstance(value, list):
        return any(v is None or _holds_none(v) for v in value)
    return False


async def _has_param(api: RosApi, req: Any) -> dict[str, Any]:
    return {"exists": await api._has_param(req.name)}


async def _delete_param(api: RosApi, req: Any) -> dict[str, Any]:
    if await api._has_param(req.name):
        with contextlib.suppress(NotFoundError):  # gone between the two calls
            await api._master("deleteParam", api._param_name(req.name))
    return {}


async def _search_param(api: RosApi, req: Any) -> dict[str, Any]:
    # rospy searches from rosapi_node's namespace, the root: ask as that node would
    master = LiveMaster(api.node.master.uri, NODE_NAME)
    try:
        found = await master.call("searchParam", req.name)
    except (NotFoundError, MasterError):
        return {"global_name": ""}
    except (UnreachableError, TimeoutExpired) as err:
        raise _MasterGoneError from err
    return {"global_name": str(found) if found else ""}


async def _get_param_names(api: RosApi, _: Any) -> dict[str, Any]:
    return {"names": [str(n) for n in await api._master("getParamNames")]}


async def _message_details(api: RosApi, req: Any) -> dict[str, Any]:
    return {"typedefs": api._typedefs(req.type, [])}


async def _service_request_details(api: RosApi, req: Any) -> dict[str, Any]:
    return {"typedefs": api._service_typedefs(req.type, 0)}


async def _service_response_details(api: RosApi, req: Any) -> dict[str, Any]:
    return {"typedefs": api._service_typedefs(req.type, 1)}


async def _get_time(api: RosApi, _: Any) -> dict[str, Any]:
    secs, nsecs = divmod(await api._now(), 1_000_000_000)
    return {"time": {"secs": secs, "nsecs": nsecs}}


#: rosapi_node's services: short name -> (its service type, its handler), as it registers them.
SERVICES: dict[str, tuple[str, Handler]] = {
    "topics": ("rosapi/Topics", _topics),
    "topics_for_type": ("rosapi/TopicsForType", _topics_for_type),
    "services": ("rosapi/Services", _services),
    "services_for_type": ("rosapi/ServicesForType", _services_for_type),
    "nodes": ("rosapi/Nodes", _nodes),
    "node_details": ("rosapi/NodeDetails", _node_details),
    "action_servers": ("rosapi/GetActionServers", _action_servers),
    "topic_type": ("rosapi/TopicType", _topic_type),
    "service_type": ("rosapi/ServiceType", _service_type),
    "publishers": ("rosapi/Publishers", _publishers),
    "subscribers": ("rosapi/Subscribers", _subscribers),
    "service_providers": ("rosapi/ServiceProviders", _service_providers),
    "service_node": ("rosapi/ServiceNode", _service_node),
    "service_host": ("rosapi/ServiceHost", _service_host),
    "message_details": ("rosapi/MessageDetails", _message_details),
    "service_request_details": ("rosapi/ServiceRequestDetails", _service_request_details),
    "service_response_details": ("rosapi/ServiceResponseDetails", _service_response_details),
    "set_param": ("rosapi/SetParam", _set_param),
    "get_param": ("rosapi/GetParam", _get_param),
    "has_param": ("rosapi/HasParam", _has_param),
    "search_param": ("rosapi/SearchParam", _search_param),
    "delete_param": ("rosapi/DeleteParam", _delete_param),
    "get_param_names": ("rosapi/GetParamNames", _get_param_names),
    "get_time": ("rosapi/GetTime", _get_time),
    "topics_and_raw_types": ("rosapi/TopicsAndRawTypes", _topics_and_raw_types),
}
