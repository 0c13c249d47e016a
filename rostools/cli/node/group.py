"""The ``rostools node`` group: its Typer app, with its commands in ``--help`` order."""

from __future__ import annotations

import typer

from rostools.cli.node import graph, kill, ping, query
from rostools.cli.register import add

app = typer.Typer(
    name="node",
    help="ROS nodes: list, info, ping, kill, machine, cleanup, and graph.",
    no_args_is_help=True,
    add_completion=False,
)
add(app, query.list_nodes, query.info, query.machine, ping.ping, kill.kill, kill.cleanup)
add(app, graph.graph_cmd)
