"""``rostools action list|info``: actions in the graph, from what the master knows."""

from __future__ import annotations

from typing import TYPE_CHECKING, Annotated, Any

import typer

from rostools.cli.action.group import app
from rostools.cli.action.shared import ActionArg, find_action
from rostools.cli.common import FormatOpt, MsgPathOpt, master, output_format, settings
from rostools.cli.output import emit
from rostools.cli.quick import action as quick
from rostools.cli.quick import runs
from rostools.cli.settings import type_store
from rostools.errors import RostoolsError, one_line

if TYPE_CHECKING:
    from rostools.msgs.spec import MsgSpec
    from rostools.msgs.store import TypeStore

UNKNOWN = "(unknown here: add its package with --msg-path)\n"
PARTS = (("goal", "Goal"), ("result", "Result"), ("feedback", "Feedback"))


@app.command("list")
@runs(quick.list_actions)
def list_actions(
    ctx: typer.Context,
    show_types: Annotated[
        bool, typer.Option("--show-types", "-t", help="The type of each action.")
    ] = False,
    fmt: FormatOpt = None,
) -> None:
    """List the actions in the graph: names with all five topics of an action."""
    quick.list_actions(settings(ctx), show_types, fmt)


def _spec(
    ctx: typer.Context, store: TypeStore, info: Any, part: str, suffix: str
) -> tuple[TypeStore, MsgSpec | None]:
    """The spec of one part; learnt from a peer's connection header if the store lacks it.

    Results and feedback come from the server's publishers; the goal only from a client's.
    """
    from rostools.cli.topic.learntype import learn_type

    stem = info.type.removesuffix("Action")
    if store.has_msg(stem + suffix):
        return store, store.msg(stem + suffix)
    if part == "goal" and not info.clients:
        return store, None
    try:
        store = learn_type(ctx, f"{info.name}/{part}", store)
        return store, store.msg(stem + suffix)
    except RostoolsError:
        return store, None


@app.command()
def info(
    ctx: typer.Context, action: ActionArg, fmt: FormatOpt = None, msg_path: MsgPathOpt = None
) -> None:
    """Type, servers, clients, and the goal, result and feedback of an action."""
    from rostools.msgs import describe

    found = find_action(master(ctx, "rostools"), action, need_server=False)
    store = type_store(msg_path)
    data = found.as_dict()
    text = [f"Action: {one_line(found.name)}", f"Type: {one_line(found.type)}", ""]
    for label, names in (("Servers", found.servers), ("Clients", found.clients)):
        text.append(f"{label}:" + ("" if names else " None"))
        text += [f" * {one_line(n)}" for n in names]
        text.append("")
    for part, suffix in PARTS:
        store, spec = _spec(ctx, store, found, part, suffix)
        data[part] = describe.structure(store, spec) if spec is not None else None
        shown = describe.show_text(store, spec) if spec is not None else UNKNOWN
        text.append(f"{part.capitalize()}:\n{shown}")
    emit(output_format(ctx, fmt), data, lambda _: "\n".join(text).rstrip("\n"))
