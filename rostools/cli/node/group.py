"""The ``rostools node`` group and what its commands share: the timeout option, warnings.

Names and the summary of several failures are in ``rostools.cli.quick.node``.
"""

from __future__ import annotations

import sys
from typing import TYPE_CHECKING, Annotated

import typer

from rostools.cli.common import FiniteFloat, settings
from rostools.cli.quick import node as quick
from rostools.errors import one_line
from rostools.rosgraph.masterapi import NODE_TIMEOUT

if TYPE_CHECKING:
    from rostools.rosgraph.nodeapi import Graph


app = typer.Typer(
    name="node",
    help="ROS nodes: list, info, ping, kill, machine, cleanup, and graph.",
    no_args_is_help=True,
    add_completion=False,
)

#: Seconds between two pings of one node, as rosnode.
PING_INTERVAL = 1.0


TimeoutOpt = Annotated[
    float,
    typer.Option(
        "--timeout",
        "-t",
        click_type=FiniteFloat(min=0.001),
        help="Seconds to wait for each node's answer.",
    ),
]


def node_graph(ctx: typer.Context, timeout: float = NODE_TIMEOUT) -> Graph:
    """The graph as this command sees it: the master, and nodes asked with ``timeout``."""
    return quick.graph(settings(ctx), timeout)


def warn(text: str) -> None:
    """One line on stderr that does not stop the command (names in it escaped)."""
    sys.stderr.write(f"rostools: {one_line(text)}\n")
