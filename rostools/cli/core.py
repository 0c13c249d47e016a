"""``rostools core``: the roscore replacement."""

from __future__ import annotations

import asyncio
from dataclasses import dataclass
from typing import Annotated

import typer

from rostools.cli import output
from rostools.cli.common import FINITE, FormatOpt, output_format
from rostools.cli.declare import command, options_record
from rostools.cli.register import add
from rostools.errors import RostoolsError
from rostools.version import __version__

app = typer.Typer(
    name="core", help="Run the bundled master and parameter server (roscore).", add_completion=False
)


@options_record
@dataclass
class RoscoreFlags:
    """roscore's own flags, taken so that scripts written for it run.

    None changes anything here: one event loop, no worker threads, no separate processes.
    """

    verbose: Annotated[bool, typer.Option("-v", help="roscore's flag; no effect.")] = False
    workers: Annotated[
        int | None, typer.Option("--numworkers", "-w", help="roscore's flag; no effect.")
    ] = None
    socket_timeout: Annotated[
        float | None,
        typer.Option("--timeout", "-t", click_type=FINITE, help="roscore's flag; no effect."),
    ] = None
    logger_level: Annotated[
        str | None, typer.Option("--master-logger-level", help="roscore's flag; no effect.")
    ] = None
    sigint_timeout: Annotated[
        float | None,
        typer.Option("--sigint-timeout", click_type=FINITE, help="roscore's flag; no effect."),
    ] = None
    sigterm_timeout: Annotated[
        float | None,
        typer.Option("--sigterm-timeout", click_type=FINITE, help="roscore's flag; no effect."),
    ] = None


@command()
def core(
    ctx: typer.Context,
    port: Annotated[
        int | None,
        typer.Option("--port", "-p", help="Port. Default: the port of ROS_MASTER_URI, else 11311."),
    ] = None,
    host: Annotated[
        str | None,
        typer.Option(
            "--host",
            help="Name or address to give out; any but a loopback one listens on every "
            "interface, and 0.0.0.0 gives out the host name. Default: ROS_HOSTNAME, ROS_IP, "
            "else loopback only.",
        ),
    ] = None,
    fmt: FormatOpt = None,
    roscore: RoscoreFlags = RoscoreFlags(),  # noqa: B008 - a record of options, never changed
) -> None:
    """Run a ROS master and parameter server until Ctrl-C (SIGINT) or SIGTERM."""
    del roscore  # accepted, and without effect
    from rostools.master.core import choose_address, run_core
    from rostools.master.server import MasterServer
    from rostools.rosgraph.masterapi import master_answers

    address = choose_address(host, port)
    local = "127.0.0.1" if address.bind == "0.0.0.0" else address.bind  # noqa: S104
    probe_uri = f"http://{local}:{address.port}/"
    if master_answers(probe_uri, timeout=1.0):
        raise RostoolsError(
            f"a master is already running at {probe_uri}",
            hint="stop it first, or use another --port",
        )
    fmt = output_format(ctx, fmt)

    def ready(master: MasterServer, run_id: str) -> None:
        info = {"uri": master.uri, "bind": address.bind, "port": master.port, "run_id": run_id}
        output.write(
            fmt,
            info,
            lambda _: (
                f"rostools core {__version__}: master and parameter server\n"
                f"ROS_MASTER_URI={master.uri}\n"
                f"listening on {address.bind}:{master.port}\n"
                f"setting /run_id to {run_id}\n"
                "parameters: /rosdistro, /rosversion, /run_id\n"
                "press Ctrl-C to stop"
            ),
        )

    asyncio.run(run_core(address, ready))


add(app, core)
