"""``rostools msg show|list|package|packages|proto``: message, service and action types."""

from __future__ import annotations

from pathlib import Path

from rostools.cli import output
from rostools.cli.declare import command
from rostools.cli.msg.lookup import Kind, matches, read_type
from rostools.cli.output import Format, emit
from rostools.cli.settings import type_store
from rostools.errors import NotFoundError, QuietExit, RostoolsError, UsageError

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from typing import Annotated, Any

    import typer

    from rostools.cli.common import FormatOpt, MsgPathOpt
    from rostools.cli.msg.options import OneLineOpt, SrvOpt, TypeArg
    from rostools.cli.settings import Settings
    from rostools.msgs.store import TypeStore


@command()
def show(
    s: Settings,
    type_name: TypeArg = None,
    raw: Annotated[
        bool, typer.Option("--raw", "-r", help="The file text, comments included.")
    ] = False,
    bag: Annotated[
        Path | None,
        typer.Option("--bag", "-b", help="Take the definition stored in this .bag or .mcap."),
    ] = None,
    fmt: FormatOpt = None,
    msg_path: MsgPathOpt = None,
) -> None:
    """Show a message, service or action definition, nested types expanded (rosmsg show)."""
    from rostools.msgs import describe

    name = read_type(type_name)
    fmt = s.output_format(fmt)
    store = type_store(msg_path)
    if bag is not None:
        store, name = _store_from_bag(store, bag, name)
    results: list[tuple[str, str, dict[str, Any]]] = []
    for kind, full in matches(store, name):
        if kind == "msg":
            spec = store.msg(full)
            text = spec.text if raw else describe.show_text(store, spec)
            data: dict[str, Any] = {"type": full, "kind": kind, "md5sum": store.md5(full)}
            data |= describe.structure(store, spec)
            data["definition"] = store.full_text(full)
        elif kind == "action":
            action = store.action(full)
            text = action.text if raw else describe.show_action_text(store, action)
            data = {"type": full, "kind": kind, "md5sum": store.md5(full)}
            for part in ("goal", "result", "feedback"):
                data[part] = describe.structure(store, getattr(action, part))
            data["messages"] = {m: store.md5(m) for m in action.messages}
            data["text"] = action.text
        else:
            srv = store.srv(full)
            text = srv.text if raw else describe.show_srv_text(store, srv)
            data = {"type": full, "kind": kind, "md5sum": store.srv_md5(full)}
            data["request"] = describe.structure(store, srv.request)
            data["response"] = describe.structure(store, srv.response)
            data["text"] = srv.text
        results.append((full, text, data))
    if fmt is Format.text:
        for full, text, _ in results:
            if "/" not in name:
                output.put(f"[{full}]:\n")
            output.put(text + "\n")
    else:
        emit(fmt, results[0][2] if "/" in name else [r[2] for r in results])


def _store_from_bag(store: TypeStore, bag: Path, name: str) -> tuple[TypeStore, str]:
    from rostools.bag.formats.connections import read_connections

    for conn in read_connections(bag):
        if conn.type == name or conn.type.rpartition("/")[2] == name:
            return store.with_definition(conn.type, conn.definition), conn.type
    raise NotFoundError(f"no connection of type {name} in {bag}")


def _emit_names(fmt: Format, names: list[str], one_line: bool) -> None:
    emit(fmt, names, lambda n: (" " if one_line else "\n").join(n))


@command("list")
def list_types(
    s: Settings, srv: SrvOpt = False, fmt: FormatOpt = None, msg_path: MsgPathOpt = None
) -> None:
    """List every message type (or service type with --srv), by package."""
    store = type_store(msg_path)
    _emit_names(s.output_format(fmt), store.types("srv" if srv else "msg"), False)


@command()
def package(
    s: Settings,
    name: Annotated[str, typer.Argument(help="A package name.")],
    one_line: OneLineOpt = False,
    srv: SrvOpt = False,
    fmt: FormatOpt = None,
    msg_path: MsgPathOpt = None,
) -> None:
    """List the message (or service) types of one package."""
    store = type_store(msg_path)
    kind: Kind = "srv" if srv else "msg"
    if name not in store.packages("msg") and name not in store.packages("srv"):
        raise NotFoundError(f"no package named {name} holds message or service types")
    # a package of the other kind only (std_srvs for messages): an empty list, as rosmsg
    types = store.types(kind, name) if name in store.packages(kind) else []
    _emit_names(s.output_format(fmt), types, one_line)


@command()
def packages(
    s: Settings, one_line: OneLineOpt = False, srv: SrvOpt = False, fmt: FormatOpt = None,
    msg_path: MsgPathOpt = None,
) -> None:  # fmt: skip
    """List the packages that hold message (or service) types."""
    store = type_store(msg_path)
    _emit_names(s.output_format(fmt), store.packages("srv" if srv else "msg"), one_line)


@command()
def proto(
    s: Settings,
    type_name: TypeArg = None,
    flow_style: Annotated[
        int | None,
        typer.Option(
            "--flow-style",
            "-f",
            min=0,
            max=1,
            help="1: one line, in brackets; 0: never brackets. Default: brackets for times and "
            "arrays of scalars.",
            show_default=False,
        ),
    ] = None,
    empty_arrays: Annotated[
        bool,
        typer.Option("--empty-arrays", "-e", help="Leave arrays empty instead of one element."),
    ] = False,
    no_quotes: Annotated[
        bool,
        typer.Option("--no-quotes", "--no-hyphens", "-H", help="Do not wrap the text in quotes."),
    ] = False,
    prefix: Annotated[
        str, typer.Option("--prefix", "-p", help="Put this before every line, e.g. an indent.")
    ] = "",
    exclude: Annotated[
        str,
        typer.Option(
            "--exclude-slots", "-x", help="Comma-separated field names to leave out, at any depth."
        ),
    ] = "",
    silent: Annotated[
        bool,
        typer.Option(
            "--silent", "-s", help="No error message on failure (the exit code still says it)."
        ),
    ] = False,
    fmt: FormatOpt = None,
    msg_path: MsgPathOpt = None,
) -> None:
    """Print a YAML template of a message, a service's request or an action's goal."""
    try:
        text = _proto_text(type_name, msg_path, flow_style, empty_arrays, exclude)
    except RostoolsError as exc:
        if silent:
            raise QuietExit(exc.exit_code) from None
        raise
    fmt = s.output_format(fmt)
    if fmt is not Format.text:
        import yaml

        emit(fmt, yaml.safe_load(text) or {})
        return
    text = "\n".join(prefix + line for line in text.split("\n"))
    output.put((text if no_quotes else f'"{text}"') + "\n")


def _proto_text(
    type_name: str | None, msg_path: list[Path] | None, flow: int | None, empty: bool, exclude: str
) -> str:
    from rostools.msgs import describe

    name = read_type(type_name)
    store = type_store(msg_path)
    found = matches(store, name)
    if len(found) > 1:
        choices = ", ".join(full for _, full in found)
        raise UsageError(f"{name} is ambiguous: {choices}", hint="give the package too")
    kind, full = found[0]
    if kind == "action":
        spec = store.action(full).goal
    else:
        spec = store.msg(full) if kind == "msg" else store.srv(full).request
    skip = frozenset(n.strip() for n in exclude.split(",") if n.strip())
    return describe.proto(
        store, spec, flow=None if flow is None else bool(flow), empty_arrays=empty, exclude=skip
    )
