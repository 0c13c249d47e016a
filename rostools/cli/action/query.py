"""``rostools action list|info``: actions in the graph, from what the master knows.

Typer-free (``rostools.cli.declare``): the launcher runs list without Typer.
"""

from __future__ import annotations

from rostools.cli.action.shared import find_action
from rostools.cli.declare import command
from rostools.cli.output import emit, lines
from rostools.errors import RostoolsError, one_line

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from typing import Annotated, Any

    import typer

    from rostools.cli.action.options import ActionArg
    from rostools.cli.common import FormatOpt, MsgPathOpt
    from rostools.cli.settings import Settings
    from rostools.msgs.spec import MsgSpec
    from rostools.msgs.store import TypeStore

UNKNOWN = "(unknown here: add its package with --msg-path)\n"
PARTS = (("goal", "Goal"), ("result", "Result"), ("feedback", "Feedback"))


@command("list", quick=True)
def list_actions(
    s: Settings,
    show_types: Annotated[
        bool, typer.Option("--show-types", "-t", help="The type of each action.")
    ] = False,
    fmt: FormatOpt = None,
) -> None:
    """List the actions in the graph: names with all five topics of an action."""
    from rostools.action.pattern import find_actions

    proxy = s.master("rostools")
    pubs, subs, _ = proxy.system_state()
    found = find_actions(proxy.topic_types(), pubs, subs)
    text = lines(f"{a.name} [{a.type}]" if show_types else a.name for a in found)
    emit(s.output_format(fmt), [a.as_dict() for a in found], lambda _: text)


def _spec(
    s: Settings, store: TypeStore, info: Any, part: str, suffix: str
) -> tuple[TypeStore, MsgSpec | None]:
    """The spec of one part; learnt from a peer's connection header if the store lacks it.

    Results and feedback come from the server's publishers; the goal only from a client's.
    """
    from rostools.cli.settings import learn_type

    stem = info.type.removesuffix("Action")
    if store.has_msg(stem + suffix):
        return store, store.msg(stem + suffix)
    if part == "goal" and not info.clients:
        return store, None
    try:
        store = learn_type(s, f"{info.name}/{part}", store)
        return store, store.msg(stem + suffix)
    except RostoolsError:
        return store, None


@command()
def info(
    s: Settings, action: ActionArg, fmt: FormatOpt = None, msg_path: MsgPathOpt = None
) -> None:
    """Type, servers, clients, and the goal, result and feedback of an action."""
    from rostools.cli.settings import type_store
    from rostools.msgs import describe

    found = find_action(s.master("rostools"), action, need_server=False)
    store = type_store(msg_path)
    data = found.as_dict()
    text = [f"Action: {one_line(found.name)}", f"Type: {one_line(found.type)}", ""]
    for label, names in (("Servers", found.servers), ("Clients", found.clients)):
        text.append(f"{label}:" + ("" if names else " None"))
        text += [f" * {one_line(n)}" for n in names]
        text.append("")
    for part, suffix in PARTS:
        store, spec = _spec(s, store, found, part, suffix)
        data[part] = describe.structure(store, spec) if spec is not None else None
        shown = describe.show_text(store, spec) if spec is not None else UNKNOWN
        text.append(f"{part.capitalize()}:\n{shown}")
    emit(s.output_format(fmt), data, lambda _: "\n".join(text).rstrip("\n"))
