"""The root Typer app. Groups are modules of this package, imported only when used."""

from __future__ import annotations

import importlib
from typing import Annotated, Any

import typer
from typer.core import TyperGroup

from rostools.cli import output
from rostools.cli.output import Format
from rostools.cli.settings import Settings
from rostools.version import __version__

#: ``name:=value`` arguments that ``rostools.cli.main`` took off the command line.
REMAPPINGS: dict[str, str] = {}

#: name -> one-line help. Each group's Typer app is ``group_app(name)``.
GROUPS: dict[str, str] = {
    "topic": "Topics: list, info, type, find, echo, hz, bw, delay, pub, plot.",
    "service": "Services: list, info, type, find, uri, args, call.",
    "action": "Actions (actionlib): list, info, send-goal, cancel, status.",
    "param": "The parameter server: list, get, set, delete, load, dump.",
    "log": "Node logs (rosconsole): echo /rosout, list, get and set logger levels.",
    "msg": "Message and service types: show, md5, list, package, packages, proto.",
    "node": "ROS nodes: list, info, ping, kill, machine, cleanup, and graph.",
    "tf": "Transforms (tf2): echo, frames, monitor, pub.",
    "bag": "Bags (.bag and MCAP): record, play, info, filter, convert, cat, plot, and more.",
    "core": "Run the bundled master and parameter server (roscore).",
    "bridge": "Serve the live graph over WebSocket to Foxglove Studio, Lichtblick and browsers.",
    "doctor": "Check this host's view of the ROS graph: master, names, nodes, sim time, clocks.",
    "demo": "Try rostools in ten seconds: a master, a talker, a service, a recording.",
    "completion": "Shell completion for bash, zsh and fish: show or install the script.",
}


def group_app(name: str) -> typer.Typer:
    """The Typer app of group ``name``.

    ``rostools.cli.<name>.group.app`` for a package (whose ``__init__`` stays free of Typer),
    ``rostools.cli.<name>.app`` for a module.
    """
    module = importlib.import_module(f"rostools.cli.{name}")
    if hasattr(module, "__path__"):
        module = importlib.import_module(f"rostools.cli.{name}.group")
    app: typer.Typer = module.app
    return app


class LazyGroup(TyperGroup):
    """A group whose subcommands are loaded from their module on first use."""

    def list_commands(self, ctx: Any) -> list[str]:
        """The group names, without importing them."""
        return list(GROUPS)

    def get_command(self, ctx: Any, cmd_name: str) -> Any:
        """Import ``rostools.cli.<name>`` and convert its Typer app."""
        if cmd_name not in GROUPS:
            return None
        command = typer.main.get_command(group_app(cmd_name))
        command.name = cmd_name
        return command


app = typer.Typer(
    cls=LazyGroup,
    name="rostools",
    help="The ROS 1 command-line tools in one CLI, no ROS installation needed.",
    no_args_is_help=True,
    pretty_exceptions_enable=False,
    add_completion=False,  # ``rostools completion`` replaces Typer's own
    context_settings={"help_option_names": ["-h", "--help"]},
)


def _version(value: bool) -> None:
    if value:
        output.line(f"rostools {__version__}")
        raise typer.Exit()


@app.callback()
def root(
    ctx: typer.Context,
    master_uri: Annotated[
        str | None,
        typer.Option(
            "--master-uri",
            help="Master XML-RPC URI. Default: ROS_MASTER_URI, then http://localhost:11311.",
            show_default=False,
        ),
    ] = None,
    fmt: Annotated[
        Format,
        typer.Option("--format", help="Output format for every command that prints data."),
    ] = Format.text,
    debug: Annotated[bool, typer.Option("--debug", help="Show tracebacks on errors.")] = False,
    version: Annotated[
        bool,
        typer.Option(
            "--version", "-V", callback=_version, is_eager=True, help="Print the version."
        ),
    ] = False,
) -> None:
    """rostools: rostopic, rosservice, rosparam, rosnode, rosmsg, rosbag and roscore in one."""
    ctx.obj = Settings(master_uri=master_uri, format=fmt, debug=debug, remappings=REMAPPINGS)
