"""What the topic commands share: their common arguments and options, and waiting for a topic."""

from __future__ import annotations

import contextlib
import sys
import time
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rostools.cli.common import FINITE

if TYPE_CHECKING:
    import asyncio

    from rostools.msgs.store import TypeStore
    from rostools.node.node import Node

TopicArg = Annotated[str, typer.Argument(help="Topic name; relative names join ROS_NAMESPACE.")]
CountOpt = Annotated[int | None, typer.Option("-n", help="Exit after this many messages.")]
TimeoutOpt = Annotated[
    float | None,
    typer.Option(
        "--timeout",
        click_type=FINITE,
        help="Give up after this many seconds (exit 5 if fewer messages than asked arrived).",
    ),
]
FilterOpt = Annotated[
    str | None,
    typer.Option(
        "--filter",
        help="Python expression over m (the message) and topic; print only where it is true.",
    ),
]


async def wait_for_topic(
    node: Node, name: str, store: TypeStore, deadline: float | None, stop: asyncio.Event
) -> Any:
    """Wait until the topic is advertised; the topic and field path."""
    import asyncio

    from rostools.rosgraph.topics import field_problem, split_field

    name = node.resolve(name)  # command-line remappings apply
    warned = False
    while True:
        types = dict(await node.master_call("getTopicTypes"))
        ref = split_field(name, types, store)
        if ref is not None:
            return ref
        if not warned:  # a typo in a field of a published topic is named
            problem = field_problem(name, types, store)
            why = f" ({problem})" if problem else ""
            sys.stderr.write(f"WARNING: topic [{name}] does not appear to be published yet{why}\n")
            warned = True
        if stop.is_set() or (deadline is not None and time.monotonic() > deadline):
            return None
        with contextlib.suppress(asyncio.TimeoutError):
            await asyncio.wait_for(stop.wait(), 0.2)
