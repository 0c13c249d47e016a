"""``rostools topic list|info|find|type``: what the master knows of topics.

echo, the rate meters (hz, bw, delay) and pub live beside this module.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rostools.cli.common import FormatOpt, MsgPathOpt, settings
from rostools.cli.quick import runs
from rostools.cli.quick import topic as quick
from rostools.cli.topic.group import app
from rostools.cli.topic.live import TopicArg


@app.command("list")
@runs(quick.list_topics)
def list_topics(
    ctx: typer.Context,
    namespace: Annotated[
        str | None, typer.Argument(help="Only topics under this namespace.")
    ] = None,
    verbose: Annotated[bool, typer.Option("--verbose", "-v", help="Types and counts.")] = False,
    pubs_only: Annotated[bool, typer.Option("-p", help="Published topics only.")] = False,
    subs_only: Annotated[bool, typer.Option("-s", help="Subscribed topics only.")] = False,
    host: Annotated[bool, typer.Option("--host", help="Group by the host of each node.")] = False,
    bag: Annotated[
        Path | None, typer.Option("--bag", "-b", help="List the topics of a bag.")
    ] = None,
    fmt: FormatOpt = None,
) -> None:
    """List topics (rostopic list)."""
    quick.list_topics(settings(ctx), namespace, verbose, pubs_only, subs_only, host, bag, fmt)


@app.command()
@runs(quick.info)
def info(ctx: typer.Context, topic: TopicArg, fmt: FormatOpt = None) -> None:
    """Type, publishers and subscribers of a topic (rostopic info)."""
    quick.info(settings(ctx), topic, fmt)


@app.command()
@runs(quick.find)
def find(
    ctx: typer.Context,
    msg_type: Annotated[str, typer.Argument(help="A message type, pkg/Type.")],
    fmt: FormatOpt = None,
) -> None:
    """Topics of a given type (rostopic find)."""
    quick.find(settings(ctx), msg_type, fmt)


@app.command("type")
@runs(quick.type_)
def type_(
    ctx: typer.Context, topic: TopicArg, fmt: FormatOpt = None, msg_path: MsgPathOpt = None
) -> None:
    """A topic's type, or the type of a field: /odom/pose/pose (rostopic type)."""
    quick.type_(settings(ctx), topic, fmt, msg_path)
