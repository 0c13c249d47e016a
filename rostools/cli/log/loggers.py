"""``rostools log list|get|set``: a node's loggers, as rosconsole list, get and set.

Through the node's ``~get_loggers`` and ``~set_logger_level`` services.

Typer-free (``rostools.cli.declare``): the launcher runs them without Typer or asyncio. The
services' bytes are ``rostools.node.loggers``'s, read with ``struct``; no type store loads.
"""

from __future__ import annotations

from rostools.cli import output
from rostools.cli.declare import command
from rostools.cli.output import Format, emit
from rostools.errors import NotFoundError, RostoolsError, UsageError, one_line
from rostools.node.loggers import (
    GET_LOGGERS,
    LEVELS,
    SET_LOGGER_LEVEL,
    LoggerBytesError,
    decode_loggers,
    encode_set,
)

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from typing import Annotated

    import typer

    from rostools.cli.common import FormatOpt
    from rostools.cli.settings import Settings
    from rostools.rosgraph.masterapi import MasterProxy

TOOL = "rosconsole"

if TYPE_CHECKING:
    NodeArg = Annotated[str, typer.Argument(help="The node; relative names join ROS_NAMESPACE.")]
    LoggerArg = Annotated[str, typer.Argument(help="A logger of the node (log list NODE).")]
    SomeLoggerArg = Annotated[
        str | None, typer.Argument(help="A logger of the node (default: every one).")
    ]
    LevelArg = Annotated[str, typer.Argument(help="debug, info, warn, error or fatal.")]


def _service(node: str, which: str) -> str:
    from rostools.names import script_resolve

    return script_resolve(node, TOOL).rstrip("/") + "/" + which


def _call(
    master: MasterProxy, node: str, suffix: str, which: tuple[str, str], request: bytes
) -> bytes:
    """Call the node's ``suffix`` service, of type ``which``; the response's bytes."""
    from rostools.cli.settings import caller_id
    from rostools.rosgraph.serviceclient import BlockingServiceClient

    name = _service(node, suffix)
    try:
        master.lookup_service(name)
    except NotFoundError:
        from rostools.names import script_resolve

        full = script_resolve(node, TOOL)
        try:
            master.lookup_node(full)
        except NotFoundError:
            raise NotFoundError(f"node {full} does not exist") from None
        raise NotFoundError(
            f"node {full} does not serve {suffix}",
            hint="only nodes with rospy's or roscpp's logger services have loggers to set",
        ) from None
    client = BlockingServiceClient(master, name)
    try:
        return client.call(caller_id(TOOL), which[1], request)
    except RostoolsError as err:
        if "md5" in str(err):  # a service of that name, of another type
            raise RostoolsError(f"{name} is not a {which[0]} service: {err}") from err
        raise


def loggers_of(master: MasterProxy, node: str) -> list[tuple[str, str]]:
    """The node's loggers and their levels, as it gives them."""
    data = _call(master, node, "get_loggers", GET_LOGGERS, b"")
    try:
        return decode_loggers(data)
    except LoggerBytesError as err:
        raise RostoolsError(f"node {node} answered get_loggers with garbage: {err}") from err


def _level_of(found: list[tuple[str, str]], node: str, logger: str) -> str:
    levels = dict(found)
    if logger not in levels:  # rosconsole's words and exit code (2)
        raise UsageError(f"node {node} does not contain logger {logger}")
    return levels[logger]


@command("list", quick=True)
def list_loggers(s: Settings, node: NodeArg, fmt: FormatOpt = None) -> None:
    """List a node's loggers (rosconsole list)."""
    found = loggers_of(s.master(TOOL), node)
    out = s.output_format(fmt)
    if out is not Format.text:
        emit(out, [{"logger": n, "level": lv} for n, lv in found])
    else:
        output.put("".join(one_line(n) + "\n" for n, _ in found))


@command(quick=True)
def get(s: Settings, node: NodeArg, logger: SomeLoggerArg = None, fmt: FormatOpt = None) -> None:
    """A logger's level (rosconsole get); every logger's, with no LOGGER."""
    found = loggers_of(s.master(TOOL), node)
    out = s.output_format(fmt)
    if logger is None:
        if out is not Format.text:
            emit(out, [{"logger": n, "level": lv} for n, lv in found])
        else:
            output.put("".join(one_line(f"{n} {lv}") + "\n" for n, lv in found))
        return
    level = _level_of(found, node, logger)
    emit(out, {"logger": logger, "level": level}, lambda d: one_line(d["level"]))


@command("set", quick=True)
def set_(s: Settings, node: NodeArg, logger: LoggerArg, level: LevelArg) -> None:
    """Set a logger's level: debug, info, warn, error or fatal (rosconsole set)."""
    # One call to the node's set_logger_level. rosconsole asks get_loggers first, to check
    # that the logger exists; Debian's roscpp nodes crash after answering that (log4cxx
    # 0.15), so the check is left to the node, which refuses what it cannot set.
    if level.lower() not in LEVELS:
        raise UsageError(f"invalid level {level!r}: one of {', '.join(LEVELS)}")
    _call(s.master(TOOL), node, "set_logger_level", SET_LOGGER_LEVEL, encode_set(logger, level))
