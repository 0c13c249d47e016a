"""``rostools service``: all of rosservice, with timeouts and one set of exit codes."""

from __future__ import annotations

import sys
import time
from typing import TYPE_CHECKING, Annotated, Any

import typer

from rostools.cli.common import FINITE, FormatOpt, MsgPathOpt, master, output_format, settings
from rostools.cli.output import Format, emit, lines
from rostools.cli.quick import runs
from rostools.cli.quick import service as quick
from rostools.cli.settings import caller_id, type_store
from rostools.errors import NotFoundError, TimeoutExpired, UsageError, one_line
from rostools.names import script_resolve
from rostools.rosgraph.masterapi import PROBE_TIMEOUT, WAIT_NOTICE

if TYPE_CHECKING:
    from rostools.msgs.store import TypeStore
    from rostools.msgs.text import TextOptions
    from rostools.rosgraph.masterapi import MasterProxy

app = typer.Typer(
    name="service",
    help="Services: list, info, type, find, uri, args, call.",
    no_args_is_help=True,
    add_completion=False,
)

ServiceArg = Annotated[str, typer.Argument(help="Service name; relative names join ROS_NAMESPACE.")]
TimeoutOpt = Annotated[
    float, typer.Option("--timeout", click_type=FINITE, help="Seconds to wait for the service.")
]
CallTimeoutOpt = Annotated[
    float | None,
    typer.Option(
        "--timeout",
        click_type=FINITE,
        help="Give up after this many seconds, for --wait and for each call (exit 5). "
        "Without it there is no limit, as with rosservice.",
        show_default=False,
    ),
]


def _srv(store: TypeStore, type_name: str, name: str) -> Any:
    try:
        return store.srv(type_name)
    except NotFoundError:
        raise NotFoundError(
            f"{name} is a {type_name}, a service type not installed here",
            hint="add its package with --msg-path",
        ) from None


@app.command("list")
@runs(quick.list_services)
def list_services(
    ctx: typer.Context,
    namespace: Annotated[
        str | None, typer.Argument(help="Only services under this namespace.")
    ] = None,
    nodes: Annotated[
        bool, typer.Option("--nodes", "-n", help="Show the node of each service.")
    ] = False,
    fmt: FormatOpt = None,
) -> None:
    """List services (rosservice list)."""
    quick.list_services(settings(ctx), namespace, nodes, fmt)


@app.command()
@runs(quick.uri)
def uri(ctx: typer.Context, service: ServiceArg, fmt: FormatOpt = None) -> None:
    """The rosrpc URI of a service."""
    quick.uri(settings(ctx), service, fmt)


@app.command()
@runs(quick.node)
def node(ctx: typer.Context, service: ServiceArg, fmt: FormatOpt = None) -> None:
    """The node that provides a service (rosservice node)."""
    quick.node(settings(ctx), service, fmt)


@app.command("type")
@runs(quick.type_)
def type_(
    ctx: typer.Context,
    service: ServiceArg,
    timeout: TimeoutOpt = PROBE_TIMEOUT,
    fmt: FormatOpt = None,
) -> None:
    """A service's type, asked of its server (rosservice type)."""
    quick.type_(settings(ctx), service, timeout, fmt)


@app.command()
def args(
    ctx: typer.Context,
    service: ServiceArg,
    timeout: TimeoutOpt = PROBE_TIMEOUT,
    fmt: FormatOpt = None,
    msg_path: MsgPathOpt = None,
) -> None:
    """The request fields of a service (rosservice args)."""
    name = script_resolve(service, "rosservice")
    kind, _ = quick.type_of(master(ctx, "rosservice"), name, timeout)
    fields = [f.name for f in _srv(type_store(msg_path), kind, name).request.fields]
    emit(output_format(ctx, fmt), fields, " ".join)


@app.command()
def info(
    ctx: typer.Context,
    service: ServiceArg,
    timeout: TimeoutOpt = PROBE_TIMEOUT,
    fmt: FormatOpt = None,
    msg_path: MsgPathOpt = None,
) -> None:
    """Node, URI, type and request fields of a service (rosservice info)."""
    name = script_resolve(service, "rosservice")
    proxy = master(ctx, "rosservice")
    providers = quick.services(proxy).get(name)
    if not providers:
        raise NotFoundError(f"unknown service {name}")
    found_uri = proxy.lookup_service(name)
    kind, md5 = quick.type_of(proxy, name, timeout)
    store = type_store(msg_path)
    request = [f.name for f in store.srv(kind).request.fields] if _has_srv(store, kind) else None
    data = {
        "service": name,
        "node": providers[0],
        "uri": found_uri,
        "type": kind,
        "md5sum": md5,
        "args": request,
    }
    shown = [f"Node: {providers[0]}", f"URI: {found_uri}", f"Type: {kind}"]
    shown.append(f"Args: {' '.join(request or [])}")
    emit(output_format(ctx, fmt), data, lambda _: lines(shown))


def _has_srv(store: TypeStore, kind: str) -> bool:
    try:
        store.srv(kind)
    except NotFoundError:
        return False
    return True


@app.command()
def find(
    ctx: typer.Context,
    srv_type: Annotated[str, typer.Argument(help="A service type, pkg/Type.")],
    timeout: TimeoutOpt = 2.0,
    fmt: FormatOpt = None,
) -> None:
    """Services of a given type, found by probing each (rosservice find)."""
    from rostools.errors import RostoolsError

    proxy = master(ctx, "rosservice")
    found = []
    for name in quick.services(proxy):
        try:
            if quick.type_of(proxy, name, timeout)[0] == srv_type:
                found.append(name)
        except RostoolsError:
            continue  # a dead or slow server is simply not a match
    emit(output_format(ctx, fmt), found, lines)


@app.command(context_settings={"ignore_unknown_options": True})
def call(
    ctx: typer.Context,
    service: ServiceArg,
    values: Annotated[
        list[str] | None,
        typer.Argument(help="Request: one YAML mapping, or one YAML value per field in order."),
    ] = None,
    verbose: Annotated[
        bool, typer.Option("--verbose", "-v", help="Print the request too.")
    ] = False,
    wait: Annotated[
        bool, typer.Option("--wait", help="Wait for the service to appear (up to --timeout).")
    ] = False,
    nostr: Annotated[bool, typer.Option("--nostr", help="Hide strings, as echo does.")] = False,
    noarr: Annotated[bool, typer.Option("--noarr", help="Hide arrays, as echo does.")] = False,
    timeout: CallTimeoutOpt = None,
    fmt: FormatOpt = None,
    msg_path: MsgPathOpt = None,
) -> None:
    """Call a service (rosservice call); stdin YAML documents make one call each."""
    from rostools.msgs.codec import Codec
    from rostools.msgs.fill import Filler, parse_yaml_args
    from rostools.msgs.text import TextOptions

    name = script_resolve(service, "rosservice")
    proxy = master(ctx, "rosservice")
    started = time.monotonic()
    if wait:
        _wait_for(proxy, name, timeout)
    left = None if timeout is None else max(timeout - (time.monotonic() - started), 0.001)
    kind, md5 = quick.type_of(proxy, name, PROBE_TIMEOUT if left is None else left)
    store = type_store(msg_path)
    spec = _srv(store, kind, name)
    codec = Codec.of(store)
    filler = Filler(codec)
    if values:
        requests = [parse_yaml_args(values)]
    elif spec.request.fields and not sys.stdin.isatty():
        from rostools import yamlio

        docs = yamlio.load_all(sys.stdin.read(), "stdin")
        requests = [[doc] for doc in docs if doc is not None]
    else:
        requests = [[]]
    fmt = output_format(ctx, fmt)
    client = quick.client(proxy, name, timeout)
    client.waiting = _say_waiting
    for arguments in requests:
        try:
            request = filler.message(spec.request.name, arguments)
        except UsageError as err:
            fields = " ".join(f.name for f in spec.request.fields) or "(none)"
            raise UsageError(f"{err}", hint=f"{name} takes: {fields}") from err
        answer = client.call(caller_id("rosservice"), md5, request.serialize())
        response = codec.decode(spec.response.name, answer)
        _print(codec, spec, request, response, verbose, fmt, TextOptions(nostr, noarr))


def _say_waiting(what: str) -> None:
    """One line on stderr once a wait without a limit has lasted ``WAIT_NOTICE`` seconds."""
    sys.stderr.write(
        f"rostools: waiting for {one_line(what)} ({WAIT_NOTICE:g} s so far; Ctrl-C stops, "
        "--timeout sets a limit)\n"
    )
    sys.stderr.flush()


def _wait_for(proxy: MasterProxy, name: str, timeout: float | None) -> None:
    """Until the master lists ``name`` (rosservice call --wait): at most ``timeout``."""
    started = time.monotonic()
    told = False
    while name not in quick.services(proxy):
        waited = time.monotonic() - started
        if timeout is not None and waited > timeout:
            raise TimeoutExpired(f"service {name} did not appear within {timeout:g} s")
        if timeout is None and not told and waited >= WAIT_NOTICE:
            _say_waiting(f"service {name} to appear")
            told = True
        time.sleep(0.1)


def _print(
    codec: Any,
    spec: Any,
    request: Any,
    response: Any,
    verbose: bool,
    fmt: Format,
    options: TextOptions,
) -> None:
    from rostools.msgs import plain, text

    if fmt is Format.text:
        out = ""
        if verbose:
            show = text.formatter(codec, text.message_type(spec.request.name), options)
            out = show(request) + "\n---\n"
        out += text.formatter(codec, text.message_type(spec.response.name), options)(response)
        sys.stdout.write(out + "\n")
    else:
        data = plain.to_plain(codec, text.message_type(spec.response.name))(response)
        if verbose:
            data = {
                "request": plain.to_plain(codec, text.message_type(spec.request.name))(request),
                "response": data,
            }
        if fmt is Format.json:
            sys.stdout.write(plain.dumps(data) + "\n")
        else:
            emit(fmt, data)
    sys.stdout.flush()
