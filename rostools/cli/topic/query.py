"""``rostools topic list|info|find|type``: what the master knows of topics.

Typer-free: the launcher runs these without Typer (``rostools.cli.declare``). echo, the rate
meters (hz, bw, delay), pub and plot live beside this module.
"""

from __future__ import annotations

from rostools.cli import output
from rostools.cli.declare import command
from rostools.cli.output import Format, emit, lines
from rostools.errors import NotFoundError, UsageError, one_line
from rostools.names import script_resolve

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from pathlib import Path
    from typing import Annotated, Any

    import typer

    from rostools.cli.common import FormatOpt, MsgPathOpt
    from rostools.cli.settings import Settings
    from rostools.cli.topic.live import TopicArg


@command("list", quick=True)
def list_topics(
    s: Settings,
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
    fmt = s.output_format(fmt)
    if pubs_only and subs_only:
        raise UsageError("-p and -s cannot be combined")
    if bag is not None:
        if pubs_only or subs_only or host:
            raise UsageError("-p, -s and --host do not apply to a bag")
        from rostools.cli.topic.bagtopics import list_bag_topics

        list_bag_topics(bag, namespace, fmt)
        return
    from rostools.rosgraph.topics import host_of, topic_table

    proxy = s.master("rostopic")
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
        output.put(list_text(table, verbose, pubs_only, subs_only) + "\n")
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
        output.put(f"Host [{one_line(hostname)}]:\n")
        output.put(list_text(by_host[hostname], verbose, pubs_only, subs_only, "  ") + "\n")


def list_text(
    table: dict[str, Any], verbose: bool, pubs_only: bool, subs_only: bool, indent: str = ""
) -> str:
    """rostopic list's text: names, or with ``verbose`` the published/subscribed blocks."""
    infos = list(table.values())
    if not verbose:
        if pubs_only:
            names = [i.name for i in infos if i.publishers]
        elif subs_only:
            names = [i.name for i in infos if i.subscribers]
        else:
            names = [i.name for i in infos]
        return "\n".join(indent + one_line(n) for n in sorted(names))
    lines: list[str] = []
    if not subs_only:
        lines += ["", f"{indent}Published topics:"]
        for i in infos:
            if i.publishers:
                n = len(i.publishers)
                lines.append(f"{indent} * {_named(i)} {n} publisher{'s' if n > 1 else ''}")
    if not pubs_only:
        lines += [indent, f"{indent}Subscribed topics:"]
        for i in infos:
            if i.subscribers:
                n = len(i.subscribers)
                lines.append(f"{indent} * {_named(i)} {n} subscriber{'s' if n > 1 else ''}")
    lines.append("")
    return "\n".join(lines)


def _named(info: Any) -> str:
    """``/name [pkg/Type]``, escaped: both are the peers'."""
    return f"{one_line(info.name)} [{one_line(info.type)}]"


@command(quick=True)
def info(s: Settings, topic: TopicArg, fmt: FormatOpt = None) -> None:
    """Type, publishers and subscribers of a topic (rostopic info)."""
    from rostools.rosgraph.topics import topic_table

    name = script_resolve(topic, "rostopic")
    proxy = s.master("rostopic")
    table = topic_table(proxy)
    entry = table.get(name)
    if entry is None:
        raise NotFoundError(f"unknown topic {name}")
    apis = {n: proxy.lookup_node(n) for n in {*entry.publishers, *entry.subscribers}}
    fmt = s.output_format(fmt)
    if fmt is not Format.text:
        data = entry.as_dict()
        data["publishers"] = [{"node": n, "uri": apis[n]} for n in entry.publishers]
        data["subscribers"] = [{"node": n, "uri": apis[n]} for n in entry.subscribers]
        emit(fmt, data)
        return
    out = [f"Type: {one_line(entry.type)}", ""]
    for label, nodes in (("Publishers", entry.publishers), ("Subscribers", entry.subscribers)):
        if nodes:
            out.append(f"{label}: ")
            out += [f" * {one_line(n)} ({one_line(apis[n])})" for n in nodes]
        else:
            out.append(f"{label}: None")
        out.append("")
    output.put("\n".join(out) + "\n\n")


@command(quick=True)
def find(
    s: Settings,
    msg_type: Annotated[str, typer.Argument(help="A message type, pkg/Type.")],
    fmt: FormatOpt = None,
) -> None:
    """Topics of a given type (rostopic find)."""
    types = s.master("rostopic").topic_types()
    found = sorted(t for t, ty in types.items() if ty == msg_type)
    emit(s.output_format(fmt), found, lines)


@command("type", quick=True)
def type_(s: Settings, topic: TopicArg, fmt: FormatOpt = None, msg_path: MsgPathOpt = None) -> None:
    """A topic's type, or the type of a field: /odom/pose/pose (rostopic type)."""
    from rostools.cli.settings import learn_type, type_store
    from rostools.msgs.topicpath import split_field

    name = script_resolve(topic, "rostopic", field_path=True)
    types = s.master("rostopic").topic_types()
    # A topic named exactly needs no types; only a field path does.
    store = None if (name.rstrip("/") or "/") in types else type_store(msg_path)
    ref = split_field(name, types, store)
    if ref is None or ref.type is None:
        raise NotFoundError(f"unknown topic type [{name}]")
    out = s.output_format(fmt)
    if not ref.field:
        emit(out, {"topic": ref.topic, "type": ref.type}, lambda d: one_line(d["type"]))
        return
    from rostools.msgs import fieldpath

    assert store is not None  # a field path was split off, so the name was no topic
    if not store.has_msg(ref.type):
        store = learn_type(s, ref.topic, store)
    path = fieldpath.resolve(store, ref.type, ref.field)
    data = {
        "topic": ref.topic,
        "type": ref.type,
        "field": ref.field,
        "field_type": path.result.type,
    }
    emit(out, data, lambda d: one_line(f"{d['type']} {d['field']} {d['field_type']}"))
