"""The Master and Parameter APIs: argument checks, ROS return triples, outgoing calls.

Sans-IO: ``MasterAPI.call(method, params)`` returns the XML-RPC result and queues the node
calls the change requires (``publisherUpdate``, ``paramUpdate``, ``shutdown``) in
``outgoing``, for the server to send. Messages and error values follow rosmaster exactly
(https://wiki.ros.org/ROS/Master_API,
https://wiki.ros.org/ROS/Parameter%20Server_API).
"""

from __future__ import annotations

import os
from typing import Any

from rostools.master.params import ParamTree, subscription_key
from rostools.master.registry import Outgoing, Registry
from rostools.names import ANYTYPE, resolve
from rostools.wire import rosapi as check
from rostools.wire.codes import ERROR, SUCCESS
from rostools.wire.rosapi import Methods, Triple
from rostools.wire.xmlrpc import multicall


class MasterAPI:
    """The state of one master and the handlers of every API method."""

    def __init__(self, uri: str, pid: int | None = None) -> None:
        self.uri = uri
        self.pid = os.getpid() if pid is None else pid
        self.registry = Registry()
        self.params = ParamTree(self.registry.param_subscribers)
        self.outgoing: list[Outgoing] = []
        self.shutdown_requested: str | None = None
        topic, service = check.graph_name("topic"), check.graph_name("service")
        caller_api, key, kind = check.api_uri("caller_api"), check.param_key, check.topic_type
        # method -> (handler, error value, argument checks after caller_id)
        self.methods: Methods = {
            "getUri": (self.getUri, "", ()),
            "getPid": (self.getPid, -1, ()),
            "shutdown": (self.shutdown, 0, (check.anything,)),
            "registerService": (
                self.registerService, 0, (service, check.api_uri("service_api"), caller_api),
            ),
            "unregisterService": (
                self.unregisterService, 0, (service, check.api_uri("service_api")),
            ),
            "registerSubscriber": (self.registerSubscriber, [], (topic, kind, caller_api)),
            "unregisterSubscriber": (self.unregisterSubscriber, 0, (topic, caller_api)),
            "registerPublisher": (self.registerPublisher, [], (topic, kind, caller_api)),
            "unregisterPublisher": (self.unregisterPublisher, 0, (topic, caller_api)),
            "lookupNode": (self.lookupNode, "", (check.node_name("node"),)),
            "lookupService": (self.lookupService, "", (service,)),
            "getPublishedTopics": (self.getPublishedTopics, 0, (check.subgraph,)),
            "getTopicTypes": (self.getTopicTypes, [], ()),
            "getSystemState": (self.getSystemState, [[], [], []], ()),
            "setParam": (self.setParam, 0, (key, check.not_none)),
            "getParam": (self.getParam, 0, (key,)),
            "deleteParam": (self.deleteParam, 0, (key,)),
            "hasParam": (self.hasParam, False, (key,)),
            "searchParam": (self.searchParam, 0, (key,)),
            "subscribeParam": (self.subscribeParam, 0, (caller_api, key)),
            "unsubscribeParam": (self.unsubscribeParam, 0, (caller_api, key)),
            "getParamNames": (self.getParamNames, [], ()),
        }  # fmt: skip

    # dispatch -------------------------------------------------------------------------

    def call(self, method: str, params: tuple[Any, ...]) -> Any:
        """Run one XML-RPC call; raises ``Fault`` (``wire.xmlvalues``) for an unknown method."""
        if method == "system.multicall":
            return multicall(self.call, params)
        return check.dispatch(self.methods, method, params)

    def cache_key(self, method: str, params: tuple[Any, ...]) -> tuple[Any, ...] | None:
        """What a cached answer to this call is kept under (see ``rosapi.cache_key``)."""
        return check.cache_key(self.methods, method, params)

    def _notify_publishers(self, topic: str) -> None:
        subscribers = self.registry.apis("sub", topic)
        if not subscribers:
            return
        pub_uris = self.registry.apis("pub", topic)
        for api in subscribers:
            self.outgoing.append(Outgoing(api, "publisherUpdate", ("/master", topic, pub_uris)))

    def _notify_params(self, updates: list[tuple[str, str, str, Any]]) -> None:
        for _, api, key, value in updates:
            self.outgoing.append(Outgoing(api, "paramUpdate", ("/master", key, value)))

    # master API -----------------------------------------------------------------------

    def getUri(self, caller_id: str) -> Triple:  # noqa: N802 - ROS API names
        """The master's URI."""
        return SUCCESS, "", self.uri

    def getPid(self, caller_id: str) -> Triple:  # noqa: N802
        """The master's process id."""
        return SUCCESS, "", self.pid

    def shutdown(self, caller_id: str, msg: Any) -> Triple:
        """Stop the master."""
        self.shutdown_requested = f"{msg}" if msg else "external shutdown request"
        return SUCCESS, "shutdown", 0

    def registerService(  # noqa: N802
        self, caller_id: str, service: str, service_api: str, caller_api: str
    ) -> Triple:
        """Register a service provider; the last one wins."""
        self.outgoing += self.registry.register("srv", service, caller_id, caller_api, service_api)
        return SUCCESS, f"Registered [{caller_id}] as provider of [{service}]", 1

    def unregisterService(self, caller_id: str, service: str, service_api: str) -> Triple:  # noqa: N802
        """Unregister a service provider, if it is still the current one."""
        return self.registry.unregister("srv", service, caller_id, service_api=service_api)

    def lookupService(self, caller_id: str, service: str) -> Triple:  # noqa: N802
        """The rosrpc URI of a service."""
        entry = self.registry.services.get(service)
        if entry is None:
            return ERROR, "no provider", ""
        return SUCCESS, f"rosrpc URI: [{entry[2]}]", entry[2]

    def registerSubscriber(  # noqa: N802
        self, caller_id: str, topic: str, topic_type: str, caller_api: str
    ) -> Triple:
        """Register a subscriber; the current publishers' URIs."""
        self.outgoing += self.registry.register("sub", topic, caller_id, caller_api)
        if topic not in self.registry.topic_types and topic_type != ANYTYPE:
            self.registry.topic_types[topic] = topic_type
        return SUCCESS, f"Subscribed to [{topic}]", self.registry.apis("pub", topic)

    def unregisterSubscriber(self, caller_id: str, topic: str, caller_api: str) -> Triple:  # noqa: N802
        """Unregister a subscriber."""
        return self.registry.unregister("sub", topic, caller_id, caller_api)

    def registerPublisher(  # noqa: N802
        self, caller_id: str, topic: str, topic_type: str, caller_api: str
    ) -> Triple:
        """Register a publisher, tell the subscribers; the current subscribers' URIs."""
        self.outgoing += self.registry.register("pub", topic, caller_id, caller_api)
        if topic_type != ANYTYPE or topic not in self.registry.topic_types:
            self.registry.topic_types[topic] = topic_type
        self._notify_publishers(topic)
        return (
            1,
            f"Registered [{caller_id}] as publisher of [{topic}]",
            self.registry.apis("sub", topic),
        )

    def unregisterPublisher(self, caller_id: str, topic: str, caller_api: str) -> Triple:  # noqa: N802
        """Unregister a publisher and, if it was one, tell the subscribers."""
        answer = self.registry.unregister("pub", topic, caller_id, caller_api)
        if answer[2]:
            self._notify_publishers(topic)
        return answer

    def lookupNode(self, caller_id: str, node: str) -> Triple:  # noqa: N802
        """A node's XML-RPC URI."""
        ref = self.registry.nodes.get(node)
        if ref is None:
            return ERROR, f"unknown node [{node}]", ""
        return SUCCESS, "node api", ref.api

    def getPublishedTopics(self, caller_id: str, subgraph: str) -> Triple:  # noqa: N802
        """Topics with at least one publisher, under ``subgraph``."""
        if subgraph and not subgraph.endswith("/"):
            subgraph += "/"
        types = self.registry.topic_types
        topics = [[t, types[t]] for t in self.registry.publishers if t.startswith(subgraph)]
        return SUCCESS, "current topics", topics

    def getTopicTypes(self, caller_id: str) -> Triple:  # noqa: N802
        """Every topic in the graph, with its type (a type is forgotten with its last user)."""
        return (
            SUCCESS,
            "current system state",
            [[t, ty] for t, ty in self.registry.topic_types.items()],
        )

    def getSystemState(self, caller_id: str) -> Triple:  # noqa: N802
        """Publishers, subscribers and services, by node name."""
        return SUCCESS, "current system state", self.registry.state()

    # parameter API --------------------------------------------------------------------

    def setParam(self, caller_id: str, key: str, value: Any) -> Triple:  # noqa: N802
        """Set a parameter; a dict replaces the subtree."""
        key = resolve(key, caller_id)
        try:
            updates = self.params.set(key, value, caller_id)
        except TypeError as err:
            return ERROR, f"Error: invalid arguments: {err}", 0
        except ValueError as err:
            return ERROR, f"ERROR: {err}", 0
        self._notify_params(updates)
        return SUCCESS, f"parameter {key} set", 0

    def getParam(self, caller_id: str, key: str) -> Triple:  # noqa: N802
        """A parameter's value, or a dict for a namespace."""
        key = resolve(key, caller_id)
        try:
            return SUCCESS, f"Parameter [{key}]", self.params.get(key)
        except KeyError:
            return ERROR, f"Parameter [{key}] is not set", 0

    def deleteParam(self, caller_id: str, key: str) -> Triple:  # noqa: N802
        """Delete a parameter or namespace."""
        key = resolve(key, caller_id)
        try:
            updates = self.params.delete(key)
        except KeyError:
            return ERROR, f"parameter [{key}] is not set", 0
        self._notify_params(updates)
        return SUCCESS, f"parameter {key} deleted", 0

    def hasParam(self, caller_id: str, key: str) -> Triple:  # noqa: N802
        """Whether a parameter is set."""
        key = resolve(key, caller_id)
        return SUCCESS, key, self.params.has(key)

    def searchParam(self, caller_id: str, key: str) -> Triple:  # noqa: N802
        """Search upwards from the caller's namespace."""
        found = self.params.search(caller_id, key)
        if found is None:
            return ERROR, f"Cannot find parameter [{key}] in an upwards search", ""
        return SUCCESS, f"Found [{found}]", found

    def subscribeParam(self, caller_id: str, caller_api: str, key: str) -> Triple:  # noqa: N802
        """Subscribe to a parameter; its value, or ``{}`` when unset."""
        key = resolve(key, caller_id)
        skey = subscription_key(key)
        self.outgoing += self.registry.register("param", skey, caller_id, caller_api)
        try:
            value = self.params.get(skey)
        except KeyError:
            value = {}
        return SUCCESS, f"Subscribed to parameter [{key}]", value

    def unsubscribeParam(self, caller_id: str, caller_api: str, key: str) -> Triple:  # noqa: N802
        """Unsubscribe from a parameter (always answers 1)."""
        key = resolve(key, caller_id)
        self.registry.unregister("param", subscription_key(key), caller_id, caller_api)
        return SUCCESS, f"Unsubscribe to parameter [{key}]", 1

    def getParamNames(self, caller_id: str) -> Triple:  # noqa: N802
        """Every parameter leaf name."""
        return SUCCESS, "Parameter names", self.params.names()
