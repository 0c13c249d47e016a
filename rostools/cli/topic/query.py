"""``rostools topic list|info|find|type``: what the master knows of topics.

echo, the rate meters (hz, bw, delay) and pub live beside this module.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Annotated, Any

import typer

from rostools.cli.common import FormatOpt, MsgPathOpt, master, output_format, type_store
from rostools.cli.output import Format, emit
from rostools.cli.topic.group import app
from rostools.cli.topic.live import TopicArg
from rostools.cli.topiclist import list_text
from rostools.errors import NotFoundError, UsageError
from rostools.names import script_resolve


@app.command("list")
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
    fmt = output_format(ctx, fmt)
    if pubs_only and subs_only:
        raise UsageError("-p and -s cannot be combined")
    if bag is not None:
        if pubs_only or subs_only or host:
            raise UsageError("-p, -s and --host do not apply to a bag")
        from rostools.cli.topic.bagtopics import list_bag_topics

        list_bag_topics(bag, namespace, fmt)
        return
    from rostools.rosgraph.topics import host_of, topic_table

    proxy = master(ctx, "rostopic")
    ns = script_resolve(namespace, "rostopic") if namespace else None
    table = topic_table(proxy, ns)
    if fmt is not Format.text:
        rows = [i.as_dict() for i in table.values()]
        if pubs_only:
            rows = [r for r in rows if r["publishers"]]
        if subs_only:
            rows = [r for r in rows if r["subscribers"]]
        emit(fmt, rows)
        return
    if not host:
        sys.stdout.write(list_text(table, verbose, pubs_only, subs_only) + "\n")
        return
    uris: dict[str, str] = {}
    by_host: dict[str, dict[str, Any]] = {}
    for info in table.values():
        for attr in ("publishers", "subscribers"):
            for node in getattr(info, attr):
                if node not in uris:
                    uris[node] = proxy.lookup_node(node)
                entry = by_host.setdefault(host_of(uris[node]), {})
                from rostools.rosgraph.topics import TopicInfo

                item = entry.setdefault(info.name, TopicInfo(info.name, info.type))
                getattr(item, attr).append(node)
    for hostname in sorted(by_host):
        sys.stdout.write(f"Host [{hostname}]:\n")
        sys.stdout.write(list_text(by_host[hostname], verbose, pubs_only, subs_only, "  ") + "\n")


@app.command()
def info(ctx: typer.Context, topic: TopicArg, fmt: FormatOpt = None) -> None:
    """Type, publishers and subscribers of a topic (rostopic info)."""
    from rostools.rosgraph.topics import topic_table

    name = script_resolve(topic, "rostopic")
    proxy = master(ctx, "rostopic")
    table = topic_table(proxy)
    entry = table.get(name)
    if entry is None:
        raise NotFoundError(f"unknown topic {name}")
    apis = {n: proxy.lookup_node(n) for n in {*entry.publishers, *entry.subscribers}}
    fmt = output_format(ctx, fmt)
    if fmt is not Format.text:
        data = entry.as_dict()
        data["publishers"] = [{"node": n, "uri": apis[n]} for n in entry.publishers]
        data["subscribers"] = [{"node": n, "uri": apis[n]} for n in entry.subscribers]
        emit(fmt, data)
        return
    out = [f"Type: {entry.type}", ""]
    for label, nodes in (("Publishers", entry.publishers), ("Subscribers", entry.subscribers)):
        if nodes:
            out.append(f"{label}: ")
            out += [f" * {n} ({apis[n]})" for n in nodes]
        else:
            out.append(f"{label}: None")
        out.append("")
    sys.stdout.write("\n".join(out) + "\n\n")


@app.command()
def find(
    ctx: typer.Context,
    msg_type: Annotated[str, typer.Argument(help="A message type, pkg/Type.")],
    fmt: FormatOpt = None,
) -> None:
    """Topics of a given type (rostopic find)."""
    types = master(ctx, "rostopic").topic_types()
    found = sorted(t for t, ty in types.items() if ty == msg_type)
    emit(output_format(ctx, fmt), found, "\n".join)


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
