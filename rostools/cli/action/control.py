"""``rostools action cancel|status``: cancel goals, and watch the server's goal table."""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rostools.cli import output
from rostools.cli.action.options import ActionArg, WaitOpt
from rostools.cli.action.shared import SERVER_WAIT, action_types, find_action
from rostools.cli.common import FormatOpt, master, node_session, output_format
from rostools.cli.declare import command
from rostools.cli.output import Format, emit, lines, write
from rostools.cli.settings import type_store
from rostools.errors import NotFoundError, QuietExit, TimeoutExpired, UsageError, one_line

if TYPE_CHECKING:
    import asyncio

    from rostools.action.client import ActionClient
    from rostools.node.node import LiveNode

#: How long ``cancel`` watches the status for the server to take the cancel (s).
CONFIRM_WAIT = 2.0


def _table(statuses: dict[str, tuple[int, str, int]]) -> list[dict[str, Any]]:
    from rostools.action.status import name

    return [
        {"goal_id": gid, "status": name(code), "text": text, "stamp": stamp / 1e9}
        for gid, (code, text, stamp) in statuses.items()
    ]


def _table_text(rows: list[dict[str, Any]]) -> str:
    if not rows:
        return "(no goals)"
    # a row a goal: the server's ids and texts are escaped so that each stays on its row
    ids = [one_line(r["goal_id"]) for r in rows]
    width = max(map(len, ids))
    table = [f"{'GOAL ID':<{width}}  {'STATUS':<10}  TEXT"]
    table += [
        f"{gid:<{width}}  {r['status']:<10}  {one_line(r['text'])}"
        for gid, r in zip(ids, rows, strict=True)
    ]
    return "\n".join(table)


async def _confirmed(
    client: ActionClient, goals: set[str], wait: float, stop: asyncio.Event
) -> None:
    """Until the server's status says it took the cancel of ``goals``, for at most ``wait``."""
    from rostools.action import status as st
    from rostools.node.session import first

    settle = time.monotonic() + wait
    while goals and time.monotonic() < settle and not stop.is_set():
        states = {g: client.statuses.get(g, (st.LOST, "", 0))[0] for g in goals}
        if all(c in st.CANCELING or c in st.TERMINAL for c in states.values()):
            return
        client.status_received.clear()
        await first(client.status_received.wait(), stop.wait(), timeout=0.1)


@command()
def cancel(
    ctx: typer.Context,
    action: ActionArg,
    goal_id: Annotated[
        str | None, typer.Argument(help="The goal to cancel (see 'action status').")
    ] = None,
    all_goals: Annotated[bool, typer.Option("--all", "-a", help="Cancel every goal.")] = False,
    timeout: WaitOpt = None,
    fmt: FormatOpt = None,
) -> None:
    """Cancel one goal, or every goal (--all); print the goals and their states after."""
    from rostools.action import status as st

    if (goal_id is None) == (not all_goals):
        raise UsageError("give a goal id or --all (not both)")
    fmt = output_format(ctx, fmt)
    info = find_action(master(ctx, "rostools"), action)
    types = action_types(type_store(), info)
    limit = timeout if timeout is not None else SERVER_WAIT

    async def main(node: LiveNode, stop: asyncio.Event) -> list[dict[str, Any]] | None:
        from rostools.action.client import ActionClient
        from rostools.node.session import first

        client = await ActionClient(node, info.name, types).start(goals=False)
        deadline = time.monotonic() + limit
        while not (client.status_received.is_set() and client.cancel_subscribers() > 0):
            if stop.is_set():
                return None
            if time.monotonic() >= deadline:
                raise TimeoutExpired(
                    f"the action server of {info.name} did not connect within {limit:g} s"
                )
            await first(stop.wait(), timeout=0.02)
        open_goals = {g for g, (code, _, _) in client.statuses.items() if code not in st.TERMINAL}
        if goal_id is not None:
            if goal_id not in client.statuses:
                raise NotFoundError(
                    f"no goal {goal_id} in the status of {info.name}",
                    hint=f"see 'rostools action status {info.name}'",
                )
            covered = {goal_id} & open_goals
        else:
            covered = open_goals
        client.cancel(goal_id or "")
        await _confirmed(client, covered, min(CONFIRM_WAIT, limit), stop)
        await client.close()
        chosen = covered if goal_id is None else {goal_id}
        return [r for r in _table(client.statuses) if r["goal_id"] in chosen]

    rows = node_session(ctx, main, "rostools_action", fmt)
    if rows is None:
        raise QuietExit(130)
    emit(
        fmt,
        rows,
        lambda r: lines(f"{x['goal_id']} {x['status']}" for x in r) or "no goal was open",
    )


@command()
def status(
    ctx: typer.Context,
    action: ActionArg,
    once: Annotated[
        bool, typer.Option("--once", "-1", help="Print the goal table once, then exit.")
    ] = False,
    timeout: WaitOpt = None,
    fmt: FormatOpt = None,
) -> None:
    """The server's goal table, printed again each time it changes (until Ctrl-C)."""
    fmt = output_format(ctx, fmt)
    info = find_action(master(ctx, "rostools"), action)
    types = action_types(type_store(), info)

    async def main(node: LiveNode, stop: asyncio.Event) -> bool:
        from rostools.action.client import ActionClient
        from rostools.node.session import first

        client = await ActionClient(node, info.name, types).start(goals=False, cancel=False)
        deadline = None if timeout is None else time.monotonic() + timeout
        shown: list[tuple[str, int, str]] | None = None
        while not stop.is_set():
            left = None if deadline is None else deadline - time.monotonic()
            if left is not None and left <= 0:
                break
            client.status_received.clear()
            if await first(client.status_received.wait(), stop.wait(), timeout=left) != 0:
                continue
            current = [(g, c, t) for g, (c, t, _) in client.statuses.items()]
            if current == shown:
                continue
            rows = _table(client.statuses)
            if fmt is Format.text:
                output.put(_table_text(rows) + ("\n" if once else "\n---\n"))
                output.flush()
            else:
                write(fmt, {"action": info.name, "goals": rows})
            shown = current
            if once:
                break
        await client.close()
        return shown is not None

    if not node_session(ctx, main, "rostools_action", fmt) and timeout is not None:
        raise TimeoutExpired(
            f"no status from the action server of {info.name} within {timeout:g} s"
        )
