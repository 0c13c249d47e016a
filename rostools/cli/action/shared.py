"""What the action commands share, without Typer: finding an action, its types, its text."""

from __future__ import annotations

from rostools.errors import NotFoundError
from rostools.names import script_resolve

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from rostools.action.pattern import ActionInfo
    from rostools.action.types import ActionTypes
    from rostools.cli.render import Renderer
    from rostools.msgs.store import TypeStore
    from rostools.rosgraph.masterapi import MasterProxy

#: How long a command waits for the server to connect when no --timeout is given (s).
SERVER_WAIT = 10.0


def find_action(proxy: MasterProxy, action: str, *, need_server: bool = True) -> ActionInfo:
    """The action ``action`` as the master sees it; NotFoundError when it is not there."""
    from rostools.action.pattern import find_actions

    name = script_resolve(action, "rostools")
    pubs, subs, _ = proxy.system_state()
    found = {a.name: a for a in find_actions(proxy.topic_types(), pubs, subs)}
    info = found.get(name)
    if info is None:
        raise NotFoundError(f"unknown action {name}", hint="see 'rostools action list'")
    if need_server and not info.servers:
        raise NotFoundError(f"no action server for {name}", hint="only clients are registered")
    if not info.type:
        raise NotFoundError(f"the master knows no type for {name}/goal")
    return info


def action_types(store: TypeStore, info: ActionInfo) -> ActionTypes:
    """The types of an action, as far as the store has them."""
    from rostools.action.types import ActionTypes

    return ActionTypes(store, info.type)


def renderer(types: ActionTypes, suffix: str) -> Renderer:
    """The renderer of one part of the action (``Goal``, ``Feedback``, ``Result``)."""
    from rostools.cli.render import Renderer

    return Renderer(types.codec, types.stem + suffix)
