"""``rostools topic list|info|find|type``: what the master knows of topics.

echo, the rate meters (hz, bw, delay) and pub live beside this module.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from rostools.cli.common import FormatOpt, MsgPathOpt, master, output_format, settings
from rostools.cli.output import emit
from rostools.cli.quick import runs
from rostools.cli.quick import topic as quick
from rostools.cli.settings import type_store
from rostools.cli.topic.group import app
from rostools.cli.topic.live import TopicArg
from rostools.errors import NotFoundError
from rostools.names import script_resolve


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
def type_(
    ctx: typer.Context, topic: TopicArg, fmt: FormatOpt = None, msg_path: MsgPathOpt = None
) -> None:
    """A topic's type, or the type of a field: ``/odom/pose/pose`` (rostopic type)."""
    from rostools.rosgraph.topics import split_field

    name = script_resolve(topic, "rostopic", field_path=True)
    store = type_store(msg_path)
    ref = split_field(name, master(ctx, "rostopic").topic_types(), store)
    if ref is None or ref.type is None:
        raise NotFoundError(f"unknown topic type [{name}]")
    fmt = output_format(ctx, fmt)
    if not ref.field:
        emit(fmt, {"topic": ref.topic, "type": ref.type}, lambda d: d["type"])
        return
    from rostools.msgs import fieldpath

    if not store.has_msg(ref.type):
        from rostools.cli.topic.learntype import learn_type

        store = learn_type(ctx, ref.topic, store)
    path = fieldpath.resolve(store, ref.type, ref.field)
    data = {
        "topic": ref.topic,
        "type": ref.type,
        "field": ref.field,
        "field_type": path.result.type,
    }
    emit(fmt, data, lambda d: f"{d['type']} {d['field']} {d['field_type']}")
