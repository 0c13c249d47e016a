"""Purging the registrations of nodes that no longer answer (``rostools node cleanup``)."""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

from rostools.errors import NotFoundError
from rostools.rosgraph.masterapi import (
    MasterError,
    MasterProxy,
)
from rostools.rosgraph.nodeapi import Graph

#: The reason rosnode gives in ``shutdown`` calls (observed on the wire).
from rostools.rosgraph.state import SystemState


@dataclass(frozen=True)
class Unregistration:
    """One call that purges a dead node's registration, made with the node's own caller id."""

    node: str
    method: str  # unregisterPublisher, unregisterSubscriber or unregisterService
    name: str  # the topic or service
    api: str  # the caller_api (topics) or service_api (services) it registered with

    @property
    def kind(self) -> str:
        """publisher, subscriber or service."""
        return self.method.removeprefix("unregister").lower()


def plan_cleanup(
    state: SystemState, dead: Mapping[str, str], service_apis: Mapping[str, str]
) -> list[Unregistration]:
    """The calls that remove every registration of the ``dead`` nodes (name -> XML-RPC URI).

    The master only removes a registration whose caller id and API match what was
    registered, so these are the calls rosnode's cleanup makes: the node's name as caller
    id, its node URI for topics, and the current ``lookupService`` URI for services
    (``service_apis``; a service missing there has gone already and is skipped).
    """
    plan: list[Unregistration] = []
    for node in sorted(dead):
        uri = dead[node]
        for method, table in (
            ("unregisterPublisher", state.publishers),
            ("unregisterSubscriber", state.subscribers),
        ):
            plan += [
                Unregistration(node, method, t, uri) for t in sorted(table) if node in table[t]
            ]
        for srv in sorted(state.services):
            if node in state.services[srv] and srv in service_apis:
                plan.append(Unregistration(node, "unregisterService", srv, service_apis[srv]))
    return plan


def service_apis(graph: Graph, nodes: Iterable[str]) -> dict[str, str]:
    """The current service URI of every service the ``nodes`` provide."""
    wanted = set(nodes)
    apis: dict[str, str] = {}
    for srv, providers in graph.state().services.items():
        if wanted.intersection(providers):
            try:
                apis[srv] = graph.master.lookup_service(srv)
            except NotFoundError:
                continue
    return apis


def apply_cleanup(master_uri: str, plan: Sequence[Unregistration]) -> list[bool]:
    """Make the calls; for each, whether the master removed something."""
    done: list[bool] = []
    proxies: dict[str, MasterProxy] = {}
    for step in plan:
        proxy = proxies.setdefault(step.node, MasterProxy(master_uri, step.node))
        try:
            done.append(proxy.call(step.method, step.name, step.api) == 1)
        except MasterError:
            done.append(False)
    return done
