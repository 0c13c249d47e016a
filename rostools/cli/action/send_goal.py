"""``rostools action send-goal``: send one goal, follow it, print its result.

Exit codes: 0 SUCCEEDED; 7 ABORTED; 8 REJECTED; 9 PREEMPTED or RECALLED by someone else;
5 when ``--timeout`` ran out; 130 on Ctrl-C; 4 when the server went away. The last three
cancel the goal on the server first (when it is still there).
"""

from __future__ import annotations

import sys
import time
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rostools.cli import output
from rostools.cli.action.options import ActionArg, WaitOpt
from rostools.cli.action.shared import SERVER_WAIT, find_action, renderer
from rostools.cli.common import FormatOpt, MsgPathOpt, master, node_session, output_format
from rostools.cli.declare import command
from rostools.cli.output import Format, write
from rostools.cli.settings import type_store
from rostools.errors import (
    GoalAborted,
    GoalPreempted,
    GoalRejected,
    QuietExit,
    TimeoutExpired,
    UnreachableError,
    UsageError,
    one_line,
)

if TYPE_CHECKING:
    import asyncio

    from rostools.action.client import ActionClient, ClientGoalHandle, GoalEvent
    from rostools.action.types import ActionTypes
    from rostools.cli.render import Renderer
    from rostools.node.node import LiveNode

#: How long a goal canceled on the way out may take to confirm it (s).
CANCEL_WAIT = 3.0


def _fill(types: ActionTypes, values: list[Any]) -> Any:
    from rostools.msgs.fill import Filler

    spec = types.store.msg(types.stem + "Goal")
    try:
        return Filler(types.codec).message(spec.name, values)
    except UsageError as err:
        fields = " ".join(f.name for f in spec.fields) or "(none)"
        raise UsageError(f"{err}", hint=f"the goal of {types.name} takes: {fields}") from err


async def _next(
    handle: ClientGoalHandle, stop: asyncio.Event, timeout: float | None
) -> GoalEvent | str:
    """The goal's next event, or "stop" (a signal), or "timeout"."""
    import asyncio

    get = asyncio.ensure_future(handle.events.get())
    stopped = asyncio.ensure_future(stop.wait())
    try:
        done, _ = await asyncio.wait(
            {get, stopped}, timeout=timeout, return_when=asyncio.FIRST_COMPLETED
        )
    finally:
        for task in (get, stopped):
            if not task.done():
                task.cancel()
    if get in done:
        return get.result()
    return "stop" if stopped in done else "timeout"


class _Printer:
    """Prints a goal's events.

    Text: feedback and result on stdout, the rest on stderr. YAML and JSON: every event a
    record of the stream on stdout.
    """

    def __init__(self, types: ActionTypes, fmt: Format, feedback: bool) -> None:
        self.types = types
        self.renderers: dict[str, Renderer] = {}
        self.fmt = fmt
        self.feedback = feedback
        self.said = -1  # the status last written on stderr (text)

    def part(self, suffix: str) -> Renderer:
        """The renderer of the action's ``Goal``, ``Feedback`` or ``Result``.

        Made when first needed: a type the store lacks is learnt from the server's header.
        """
        found = self.renderers.get(suffix)
        if found is None:
            found = self.renderers[suffix] = renderer(self.types, suffix)
        return found

    def say(self, line: str) -> None:
        sys.stderr.write(one_line(line) + "\n")  # goal ids and texts are the server's
        sys.stderr.flush()

    def event(self, record: dict[str, Any], line: str | None = None) -> None:
        if self.fmt is Format.text:
            if line is not None:
                self.say(line)
        else:
            write(self.fmt, record)

    def goal(self, handle: ClientGoalHandle, goal: Any) -> None:
        record = {"event": "goal", "goal_id": handle.id, "goal": self.part("Goal").plain(goal)}
        self.event(record, f"goal {handle.id} sent")

    def show(self, event: GoalEvent) -> None:
        from rostools.action.status import name

        status = name(event.status)
        record: dict[str, Any] = {
            "event": event.kind,
            "goal_id": event.goal_id,
            "status": status,
            "text": event.text,
        }
        if event.kind == "feedback":
            if not self.feedback:
                return
            record["feedback"] = self.part("Feedback").plain(event.message)
        elif event.kind == "result":
            record["result"] = self.part("Result").plain(event.message)
        if self.fmt is not Format.text:
            write(self.fmt, record)
            return
        if event.kind != "feedback" and event.status != self.said:
            self.said = event.status
            self.say(f"goal {event.goal_id}: {status}" + (f" ({event.text})" if event.text else ""))
        suffix = {"feedback": "Feedback", "result": "Result"}.get(event.kind)
        if suffix is not None:
            shown = self.part(suffix).text(event.message)
            ending = "\n---\n" if event.kind == "feedback" else "\n"
            output.put(shown + ending if shown else "")
            output.flush()


def _outcome(event: GoalEvent, name: str) -> None:
    """Raise the error of a goal that did not succeed."""
    from rostools.action import status as st

    why = f" ({event.text})" if event.text else ""
    what = f"goal {event.goal_id} of {name}"
    if event.status == st.SUCCEEDED:
        return
    if event.status == st.ABORTED:
        raise GoalAborted(f"{what} was aborted{why}")
    if event.status == st.REJECTED:
        raise GoalRejected(f"{what} was rejected{why}")
    if event.status in (st.PREEMPTED, st.RECALLED):
        raise GoalPreempted(f"{what} was canceled: {st.name(event.status)}{why}")
    if event.status == st.LOST:
        raise UnreachableError(f"{what} was lost: {event.text}", hint="did its node die?")
    raise UnreachableError(f"{what} ended in an unknown state {event.status}")


async def _server_connected(
    client: ActionClient,
    name: str,
    deadline: float | None,
    timeout: float | None,
    stop: asyncio.Event,
) -> None:
    """Until the action server connects: by the deadline, else ``SERVER_WAIT`` seconds."""
    from rostools.node.session import first

    wait_until = deadline if deadline is not None else time.monotonic() + SERVER_WAIT
    while not client.server_connected():
        if stop.is_set():
            raise QuietExit(130)
        if time.monotonic() >= wait_until:
            limit = timeout if timeout is not None else SERVER_WAIT
            raise TimeoutExpired(
                f"the action server of {name} did not connect within {limit:g} s",
                hint="is its node running, and can it reach this host?",
            )
        await first(stop.wait(), timeout=0.02)


async def _cancel(handle: ClientGoalHandle, printer: _Printer, reason: str) -> None:
    """Leaving early: cancel the goal on the server, and show what it says for a moment."""
    import asyncio

    handle.cancel()
    printer.event(
        {"event": "cancel", "goal_id": handle.id, "reason": reason},
        f"canceling goal {handle.id} ({reason})",
    )
    end, never = time.monotonic() + CANCEL_WAIT, asyncio.Event()
    while (left := end - time.monotonic()) > 0:
        got = await _next(handle, never, left)
        if isinstance(got, str):
            break
        printer.show(got)
        if got.kind in ("result", "lost"):
            break


@command("send-goal", context_settings={"ignore_unknown_options": True})
def send_goal(
    ctx: typer.Context,
    action: ActionArg,
    goal: Annotated[
        list[str] | None,
        typer.Argument(help="The goal: one YAML mapping, or one YAML value per field in order."),
    ] = None,
    feedback: Annotated[
        bool, typer.Option("--feedback", "-f", help="Print the feedback as it comes.")
    ] = False,
    timeout: WaitOpt = None,
    fmt: FormatOpt = None,
    msg_path: MsgPathOpt = None,
) -> None:
    """Send a goal and wait for its result; Ctrl-C or --timeout cancels it on the server."""
    from rostools.cli.action.shared import action_types
    from rostools.msgs.fill import parse_yaml_args

    fmt = output_format(ctx, fmt)
    values = parse_yaml_args(goal or [])
    started = time.monotonic()
    info = find_action(master(ctx, "rostools"), action)
    types = action_types(type_store(msg_path), info)
    if types.known("Goal"):
        _fill(types, values)  # a mistake is a usage error before any node starts
    deadline = started + timeout if timeout is not None else None
    printer = _Printer(types, fmt, feedback)

    async def main(node: LiveNode, stop: asyncio.Event) -> None:
        from rostools.action.client import ActionClient

        client = await ActionClient(node, info.name, types).start()
        await _server_connected(client, info.name, deadline, timeout, stop)
        message = _fill(types, values)
        handle = client.send_goal(message)
        printer.goal(handle, message)
        while True:
            left = None if deadline is None else max(deadline - time.monotonic(), 0.0)
            got = await _next(handle, stop, left)
            if isinstance(got, str):
                break
            printer.show(got)
            if got.kind in ("result", "lost"):
                await client.close()
                _outcome(got, info.name)
                return
        reason = "interrupted" if got == "stop" else "timeout"
        await _cancel(handle, printer, reason)
        await client.close()
        if reason == "interrupted":
            raise QuietExit(130)
        raise TimeoutExpired(
            f"goal {handle.id} of {info.name} did not finish within {timeout:g} s; canceled it"
        )

    node_session(ctx, main, "rostools_action", fmt)
