"""``rostools topic pub``: publish from YAML, positional values, a file or stdin."""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Callable, Iterator
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rostools.cli import output
from rostools.cli.common import FINITE, MsgPathOpt, node_session, settings
from rostools.cli.declare import command
from rostools.cli.settings import type_store
from rostools.cli.topic.live import TimeoutOpt, TopicArg
from rostools.errors import NotFoundError, RostoolsError, UsageError, one_line
from rostools.names import script_resolve

if TYPE_CHECKING:
    import asyncio

    from rostools.msgs.topictype import TopicType
    from rostools.node.node import LiveNode
    from rostools.node.publisher import TopicPublisher

#: How long ``-1`` stays up so that late subscribers still get the latched message (rostopic).
ONCE_LINGER = 3.0
#: Rate for messages from a file or stdin when none is given (rostopic).
STREAM_RATE = 10.0
#: How long messages from a file or stdin wait for a first subscriber (rostopic).
SUBSCRIBER_WAIT = 5.0
#: How long ``--use-rostime`` waits for a first ``/clock`` under sim time.
CLOCK_WAIT = 2.0
#: Waits shorter than this are slept with ``time.sleep``; asyncio wakes a millisecond late.
FINE_SLEEP = 0.002
#: Waits shorter than this are not slept at all: the next message is as good as due.
SPIN = 0.00005
#: The longest the event loop goes unserved between paced messages.
YIELD_PERIOD = 0.001
#: At most this many messages per event-loop turn, so that sockets keep being served.
MAX_BURST = 5000


def _message_source(
    filler: Any,
    type_name: str,
    args: list[str],
    file: Path | None,
    substitute: bool,
    now: Callable[[], Any],
) -> tuple[Callable[[], Iterator[Any]], bool]:
    """A generator of messages, and whether it is one message repeated.

    ``now`` gives the time that ``now`` and ``auto`` stand for when ``-s`` re-evaluates them.
    """
    from rostools.msgs.fill import parse_yaml_args

    spec = filler.codec.store.msg(type_name)
    if file is not None:
        if args:
            raise UsageError("give message values or --file, not both")
        try:
            text = file.read_text()
        except OSError as err:
            raise NotFoundError(f"cannot read {file}: {err.strerror}") from err
        except UnicodeDecodeError as err:
            raise UsageError(f"{file} is not UTF-8 text (byte {err.start})") from err
        docs = _yaml_docs(text, str(file))
        return (lambda: (filler.message(type_name, [d]) for d in docs)), len(docs) == 1
    if args:
        values = parse_yaml_args(args)
        if substitute:
            return (lambda: _forever(lambda: _refill(filler, type_name, values, now))), True
        msg = filler.message(type_name, values)
        return (lambda: _forever(lambda: msg)), True
    if not spec.fields:
        msg = filler.message(type_name, [])
        return (lambda: _forever(lambda: msg)), True
    if sys.stdin.isatty():
        raise UsageError("give message values (YAML), --file, or pipe YAML documents on stdin")
    return (lambda: (filler.message(type_name, [d]) for d in _stdin_docs())), False


def _refill(filler: Any, type_name: str, values: list[Any], now: Callable[[], Any]) -> Any:
    filler.now = now()
    return filler.message(type_name, values)


def _forever(make: Callable[[], Any]) -> Iterator[Any]:
    while True:
        yield make()


def _yaml_docs(text: str, source: str) -> list[Any]:
    from rostools import yamlio

    return [d for d in yamlio.load_all(text, source) if d is not None]


def _stdin_docs() -> Iterator[Any]:
    """YAML documents from stdin, each as soon as its ``---`` (or EOF) arrives."""
    lines: list[str] = []
    for line in sys.stdin:
        if line.rstrip() == "---":
            if lines:
                yield from _yaml_docs("".join(lines), "stdin")
            lines = []
        else:
            lines.append(line)
    if lines:
        yield from _yaml_docs("".join(lines), "stdin")


async def _ros_now(node: LiveNode, stop: asyncio.Event, limit: float | None) -> Callable[[], Any]:
    """A function giving ROS time; under sim time, once the first ``/clock`` has come.

    It waits for that at most ``CLOCK_WAIT`` seconds (or the --timeout); rospy would stamp 0.
    """
    from rostools.msgs.message import Time
    from rostools.node.clock import RosClock
    from rostools.node.session import first

    clock = RosClock()
    await clock.start(node)
    give_up = time.monotonic() + (CLOCK_WAIT if limit is None else min(CLOCK_WAIT, limit))
    while not clock.valid and not stop.is_set() and time.monotonic() < give_up:
        await first(stop.wait(), timeout=0.02)
    return lambda: Time(*divmod(clock.now(), 1_000_000_000))


@command(context_settings={"ignore_unknown_options": True})
def pub(
    ctx: typer.Context,
    topic: TopicArg,
    msg_type: Annotated[str, typer.Argument(help="Message type, pkg/Type.")],
    args: Annotated[
        list[str] | None,
        typer.Argument(help="Values: one YAML mapping, or one YAML value per field in order."),
    ] = None,
    rate: Annotated[
        float | None,
        typer.Option(
            "--rate", "-r", click_type=FINITE, help="Publish repeatedly at this rate (Hz)."
        ),
    ] = None,
    once: Annotated[
        bool, typer.Option("--once", "-1", help="Publish once, stay 3 s, exit.")
    ] = False,
    latch: Annotated[
        bool, typer.Option("--latch", "-l", help="Latch (with -r, -f or stdin).")
    ] = False,
    file: Annotated[
        Path | None, typer.Option("--file", "-f", help="YAML documents, one message each.")
    ] = None,
    substitute: Annotated[
        bool,
        typer.Option("--substitute-keywords", "-s", help="Re-evaluate now/auto for each message."),
    ] = False,
    verbose: Annotated[
        bool, typer.Option("--verbose", "-v", help="Print each message published.")
    ] = False,
    use_rostime: Annotated[
        bool,
        typer.Option(
            "--use-rostime", help="now/auto are ROS time (/clock under /use_sim_time), not wall."
        ),
    ] = False,
    timeout: TimeoutOpt = None,
    msg_path: MsgPathOpt = None,
) -> None:
    """Publish messages (rostopic pub). By default: once, latched, until Ctrl-C."""
    if rate is not None and not 0 < rate < math.inf:  # nan compares false both ways
        raise UsageError("--rate must be a number above 0")
    if once and rate is not None:
        raise UsageError("-1 and -r cannot be combined")
    name = script_resolve(topic, "rostopic")
    plan = _Plan(
        name, _store_for(ctx, name, msg_type, msg_path), msg_type, args or [], file,
        rate=rate, once=once, latch=latch, substitute=substitute, verbose=verbose,
        timeout=timeout,
    )  # fmt: skip
    node_session(ctx, partial(_publish, plan, use_rostime), "rostools_pub")


def _store_for(ctx: typer.Context, name: str, msg_type: str, msg_path: list[Path] | None) -> Any:
    """The type store with ``msg_type``: installed, or learnt from a publisher of ``name``."""
    store = type_store(msg_path)
    if store.has_msg(msg_type):
        return store
    from rostools.cli.settings import learn_type

    try:
        store = learn_type(settings(ctx), name, store)
    except Exception:  # noqa: BLE001 - no publisher to learn from: the type is unknown
        raise NotFoundError(
            f"invalid message type: {msg_type}", hint="add it with --msg-path"
        ) from None
    if not store.has_msg(msg_type):
        raise NotFoundError(f"invalid message type: {msg_type}")
    return store


class _Plan:
    """What ``pub`` publishes and how: the command line, read once."""

    def __init__(
        self,
        name: str,
        store: Any,
        msg_type: str,
        args: list[str],
        file: Path | None,
        *,
        rate: float | None,
        once: bool,
        latch: bool,
        substitute: bool,
        verbose: bool,
        timeout: float | None,
    ) -> None:
        from rostools.msgs.codec import Codec
        from rostools.msgs.fill import Filler
        from rostools.msgs.message import Time
        from rostools.msgs.text import formatter, message_type
        from rostools.msgs.topictype import TopicType

        self.name, self.msg_type, self.args, self.file = name, msg_type, args, file
        self.filler = Filler(Codec.of(store))
        self.ttype = TopicType.of(store, msg_type)
        self.substitute, self.once, self.timeout = substitute, once, timeout
        self.source, repeated = self.messages(Time.now)
        self.streamed = file is not None or (not args and not repeated)
        # a file's documents are sent once each unless a rate is given
        self.repeated = repeated and not (file is not None and rate is None)
        self.rate = STREAM_RATE if self.streamed and rate is None else rate
        self.latched = latch or (self.rate is None and not self.streamed) or once
        #: -v: each message as rostopic prints it
        self.show = formatter(self.filler.codec, message_type(msg_type)) if verbose else None

    def messages(self, now: Callable[[], Any]) -> tuple[Callable[[], Iterator[Any]], bool]:
        """The source of messages (``now`` stands for ``now``/``auto``), and if it repeats one."""
        return _message_source(
            self.filler, self.msg_type, self.args, self.file, self.substitute, now
        )


async def _publish(plan: _Plan, use_rostime: bool, node: LiveNode, stop: asyncio.Event) -> None:
    """Advertise, then publish one latched message or a paced stream, until done or stopped."""
    from rostools.rosgraph.masterapi import within

    deadline = time.monotonic() + plan.timeout if plan.timeout is not None else None
    known = await node.master.topic_types(within(deadline))  # before ours replaces it
    publisher = await node.advertise(plan.name, plan.ttype, latch=plan.latched, queue_size=1000)
    refused = _watch_types(known.get(plan.name), publisher, plan.name, plan.ttype)

    def left() -> float | None:
        return None if deadline is None else max(deadline - time.monotonic(), 0)

    source = plan.source
    if use_rostime:
        now = await _ros_now(node, stop, left())
        plan.filler.now = now()
        source = plan.messages(now)[0]
    if plan.rate is None:
        await _latch_one(plan, publisher, next(source()), refused, left, stop)
        return
    if plan.file is not None and plan.repeated:
        sys.stderr.write("Got one message and a rate, publishing repeatedly\n")  # rostopic's
    if plan.streamed:  # rostopic waits up to 5 s for a subscriber before a file or stdin
        from rostools.node.session import first

        give_up = time.monotonic() + SUBSCRIBER_WAIT
        while publisher.subscriber_count == 0 and time.monotonic() < give_up:
            if await first(stop.wait(), timeout=0.05) == 0:
                return
    await _paced(plan, publisher, source(), left, stop)


async def _latch_one(
    plan: _Plan,
    publisher: TopicPublisher,
    msg: Any,
    refused: set[str],
    left: Callable[[], float | None],
    stop: asyncio.Event,
) -> None:
    """Publish one latched message and wait: for ever, for ``-1``'s 3 s, or to the timeout."""
    from rostools.node.session import first

    publisher.publish(msg.serialize())
    note = f" for {ONCE_LINGER} seconds" if plan.once else ". Press ctrl-C to terminate"
    what = "message" if plan.show is None else f"[{plan.show(msg)}]"  # rostopic's words
    sys.stderr.write(f"publishing and latching {what}{note}\n")
    linger = left()
    if plan.once:
        linger = ONCE_LINGER if linger is None else min(ONCE_LINGER, linger)
    await first(stop.wait(), timeout=linger)
    if plan.once and refused and publisher.subscriber_count == 0:
        raise RostoolsError(
            f"no subscriber of {plan.name} took the message: "
            f"{', '.join(sorted(refused))} wanted another type"
        )


async def _paced(
    plan: _Plan,
    publisher: TopicPublisher,
    messages: Iterator[Any],
    left: Callable[[], float | None],
    stop: asyncio.Event,
) -> None:
    """Publish ``messages`` at the plan's rate until they end, the timeout, or a stop."""
    import asyncio

    from rostools.node.clock import tighten_timer_slack
    from rostools.node.session import first

    assert plan.rate is not None
    rate, show = plan.rate, plan.show
    reuse = plan.repeated and not plan.substitute
    cached: bytes | None = None
    said = ""  # -v: what each message sent prints, as rostopic prints it every time
    tighten_timer_slack()
    start, sent = time.monotonic(), 0
    served = start
    while not stop.is_set():
        due = int((time.monotonic() - start) * rate) + 1 - sent
        for _ in range(min(due, MAX_BURST)):
            if not (reuse and cached is not None):
                msg = next(messages, None)
                if msg is None:
                    return
                cached = msg.serialize()
                said = f"publishing {show(msg)}\n" if show is not None else ""
            publisher.publish(cached)
            if said:
                output.put(said)
            sent += 1
        wait = start + sent / rate - time.monotonic()
        limit = left()
        if limit is not None:
            if limit <= 0:
                return
            wait = min(wait, limit)
        if wait >= SPIN:
            publisher.flush()  # paced: each message leaves when due, not with later ones
        if wait > FINE_SLEEP:
            await first(stop.wait(), timeout=wait - FINE_SLEEP)
            served = time.monotonic()
        elif wait >= SPIN:  # asyncio wakes in whole ms: 10 kHz came in bursts
            time.sleep(wait)
        if time.monotonic() - served > YIELD_PERIOD:
            await asyncio.sleep(0)  # new subscribers, Ctrl-C and coalesced writes
            served = time.monotonic()


def _watch_types(
    carried: str | None, publisher: TopicPublisher, name: str, ttype: TopicType
) -> set[str]:
    """Say when the topic carries another type, and each subscriber that refuses ours.

    rospy's publisher logs "topic types do not match" and carries on; the messages reach no
    one. Returns the set the refusing subscribers' caller ids are added to.
    """
    from rostools.wire.tcpros import check_subscription

    if carried not in (None, ttype.type, "*"):
        sys.stderr.write(
            one_line(f"WARNING: {name} carries {carried}, not {ttype.type}: its subscribers")
            + " will refuse these messages\n"
        )
    refused: set[str] = set()

    def check(fields: dict[str, str]) -> None:
        problem = check_subscription(fields, name, ttype.md5sum, ttype.type)
        caller = fields.get("callerid", "?")
        if problem is not None and caller not in refused:
            refused.add(caller)
            sys.stderr.write(one_line(f"WARNING: {caller} refused the messages: {problem}") + "\n")

    publisher.on_subscriber = check
    return refused
