"""What every command shares on the Typer side: the common options, the settings of a run."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, TypeVar

import typer

from rostools.cli import output
from rostools.cli.output import Format
from rostools.cli.settings import Settings

T = TypeVar("T")

if TYPE_CHECKING:
    from collections.abc import Awaitable, Callable

    from rostools.node.notice import Notice
    from rostools.rosgraph.masterapi import MasterProxy

try:
    from typer._click.types import FloatRange
except ImportError:  # pragma: no cover - older typer uses the click package
    from click.types import FloatRange  # type: ignore[no-redef,import-not-found,assignment,unused-ignore]


class FiniteFloat(FloatRange):  # type: ignore[misc,unused-ignore]
    """A float option: ``nan`` and ``inf`` are usage errors (exit 2), not crashes later."""

    def convert(self, value: Any, param: Any, ctx: Any) -> Any:
        """Click's float (in range, if one is given), finite."""
        number = super().convert(value, param, ctx)
        if not math.isfinite(number):
            self.fail(f"{value!r} is not a finite number", param, ctx)
        return number


#: Every float option's type (``typer.Option(..., click_type=FINITE)``); with bounds,
#: ``FiniteFloat(min=...)`` (typer ignores ``min=`` once a ``click_type`` is given).
FINITE = FiniteFloat()


def settings(ctx: typer.Context) -> Settings:
    """The global settings of this invocation."""
    root = ctx.find_root()
    if not isinstance(root.obj, Settings):
        root.obj = Settings()
    return root.obj


def output_format(ctx: typer.Context, local: Format | None) -> Format:
    """A command's ``--format`` wins over the global one."""
    return settings(ctx).output_format(local)


def master(ctx: typer.Context, tool: str) -> MasterProxy:
    """A master client for this invocation, named like rospy tools name themselves."""
    return settings(ctx).master(tool)


def node_session(
    ctx: typer.Context,
    main: Callable[[Any, Any], Awaitable[T]],
    name: str,
    fmt: Format = Format.text,
) -> T:
    """Run ``main(node, stop)`` as an anonymous node named after ``name``.

    The command line's remapping arguments (``__name:=``, ``a:=b``, ...) apply to it. The
    node's notices go to stderr; a stream printed with ``fmt`` json also carries them as
    ``{"event": ...}`` objects.
    """
    from rostools.node.notice import to_stderr
    from rostools.node.session import run_node

    def notify(notice: Notice) -> None:
        to_stderr(notice)
        if fmt is not Format.text:  # in the stream, a record among the others
            output.write(fmt, notice.as_json())

    s = settings(ctx)
    return run_node(main, s.resolved_master_uri(), name, remappings=s.remappings, notify=notify)


#: Every command that reads MCAP messages takes it (bag doctor always checks).
NoCrcCheckOpt = Annotated[
    bool,
    typer.Option(
        "--no-crc-check",
        help="Read MCAP chunks without checking their CRCs (faster for big uncompressed"
        " messages; a damaged chunk then reads as it is).",
    ),
]
FormatOpt = Annotated[
    Format | None,
    typer.Option(
        "--format", "-F", help="Output format (overrides the global --format).", show_default=False
    ),
]
MsgPathOpt = Annotated[
    list[Path] | None,
    typer.Option(
        "--msg-path",
        help="A folder of ROS packages with msg/ and srv/ folders (repeatable; also "
        "ROSTOOLS_MSG_PATH).",
        show_default=False,
    ),
]
