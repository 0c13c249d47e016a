"""What the topic commands share: their common arguments and options, and waiting for a topic."""

from __future__ import annotations

import contextlib
import sys
import time
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rostools.cli.common import FINITE
from rostools.errors import UsageError, one_line

if TYPE_CHECKING:
    import asyncio

    from rostools.msgs.codec import DecodeError
    from rostools.msgs.store import TypeStore
    from rostools.node.connection import Frame, InboundConnection
    from rostools.node.node import LiveNode

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
StrictOpt = Annotated[
    bool,
    typer.Option(
        "--strict",
        help="Stop at a message that does not decode (exit 1), rather than skip it and say so.",
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
    node: LiveNode, name: str, store: TypeStore, deadline: float | None, stop: asyncio.Event
) -> Any:
    """Wait until the topic is advertised; the topic and field path (None: stopped, or late).

    Each question to the master takes at most what is left before ``deadline``.
    """
    import asyncio

    from rostools.errors import TimeoutExpired
    from rostools.msgs.topicpath import field_problem, split_field
    from rostools.rosgraph.masterapi import master_timeout, within

    name = node.resolve(name)  # command-line remappings apply
    warned = False
    while True:
        limit = within(deadline)
        try:
            types = await node.master.topic_types(limit)
        except TimeoutExpired:
            if limit >= master_timeout():  # the master's own limit, not what was left of ours
                raise
            return None  # the command's own timeout, said in its own words
        ref = split_field(name, types, store)
        if ref is not None:
            return ref
        if not warned:
            # a field the published topic's type does not have is a typo: said at once
            problem = field_problem(name, types, store)
            if problem is not None:  # it may name a peer's type
                raise UsageError(f"{name}: {problem}")
            line = f"WARNING: topic [{name}] does not appear to be published yet"
            sys.stderr.write(one_line(line) + "\n")
            warned = True
        if stop.is_set() or (deadline is not None and time.monotonic() > deadline):
            return None
        with contextlib.suppress(asyncio.TimeoutError):
            await asyncio.wait_for(stop.wait(), 0.2)


class Undecodable:
    """Messages that do not decode as their publisher's type says, as rostopic: skipped.

    A publisher's first is a notice naming it, the topic and the cause; the others are
    counted, and ``report`` sums them up at the end. With ``strict`` (``--strict``, for CI),
    the first ends the command instead.
    """

    def __init__(self, node: LiveNode, strict: bool) -> None:
        self.node = node
        self.strict = strict
        #: Messages skipped per publisher (its caller id, or its URI).
        self.counts: dict[str, int] = {}

    def skip(self, err: DecodeError, conn: InboundConnection, data: Frame) -> None:
        """Skip one message (``err`` names the topic and type), or raise ``err`` if strict."""
        from rostools.node.notice import Notice

        if self.strict:
            raise err
        who = (conn.header or {}).get("callerid") or conn.publisher_uri
        self.counts[who] = self.counts.get(who, 0) + 1
        if self.counts[who] == 1:
            text = f"skipped a {len(data)}-byte message from {who}: {err} (--strict stops instead)"
            fields = {"node": who, "uri": conn.publisher_uri, "reason": str(err)}
            self.node.notify(Notice("message_skipped", text, fields))

    def report(self) -> None:
        """One line for the skipped messages that no notice counted."""
        from rostools.node.notice import Notice

        total = sum(self.counts.values())
        if total > len(self.counts):
            who = ", ".join(sorted(self.counts))
            self.node.notify(
                Notice(
                    "messages_skipped",
                    f"skipped {total} messages that did not decode, from {who}",
                    {"count": total, "nodes": sorted(self.counts)},
                )
            )
