"""``rostools service call``: one call per request, with rosservice's waits and text."""

from __future__ import annotations

import sys
import time

from rostools.cli import output
from rostools.cli.declare import command
from rostools.cli.output import Format, emit
from rostools.cli.render import Renderer
from rostools.cli.service.shared import TOOL, client, service_spec, services, type_of
from rostools.cli.settings import caller_id, type_store
from rostools.errors import TimeoutExpired, UsageError, one_line
from rostools.names import script_resolve
from rostools.rosgraph.masterapi import PROBE_TIMEOUT, WAIT_NOTICE

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from typing import Annotated, Any

    import typer

    from rostools.cli.common import FormatOpt, MsgPathOpt
    from rostools.cli.service.options import CallTimeoutOpt, ServiceArg
    from rostools.cli.settings import Settings
    from rostools.rosgraph.masterapi import MasterProxy


@command(context_settings={"ignore_unknown_options": True})
def call(
    s: Settings,
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

    name = script_resolve(service, TOOL)
    proxy = s.master(TOOL)
    started = time.monotonic()
    if wait:
        _wait_for(proxy, name, timeout)
    left = None if timeout is None else max(timeout - (time.monotonic() - started), 0.001)
    kind, md5 = type_of(proxy, name, PROBE_TIMEOUT if left is None else left)
    store = type_store(msg_path)
    spec = service_spec(store, kind, name)
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
    out = s.output_format(fmt)
    shown = TextOptions(nostr, noarr)
    asks, answers = (
        Renderer(codec, m.name, text_options=shown) for m in (spec.request, spec.response)
    )
    server = client(proxy, name, timeout)
    server.waiting = _say_waiting
    for arguments in requests:
        try:
            request = filler.message(spec.request.name, arguments)
        except UsageError as err:
            fields = " ".join(f.name for f in spec.request.fields) or "(none)"
            raise UsageError(f"{err}", hint=f"{name} takes: {fields}") from err
        answer = server.call(caller_id(TOOL), md5, request.serialize())
        response = codec.decode(spec.response.name, answer)
        _print(asks, answers, (request, response), verbose, out)


def _say_waiting(what: str) -> None:
    """One line on stderr once a wait without a limit has lasted ``WAIT_NOTICE`` seconds."""
    sys.stderr.write(
        f"rostools: waiting for {one_line(what)} ({WAIT_NOTICE:g} s so far; Ctrl-C stops, "
        "--timeout sets a limit)\n"
    )
    sys.stderr.flush()


def _wait_for(proxy: MasterProxy, name: str, timeout: float | None) -> None:
    """Until the master lists ``name`` (rosservice call --wait): at most ``timeout``.

    Each question to the master takes at most what is left of ``timeout``.
    """
    from rostools.rosgraph.masterapi import master_timeout, within

    started = time.monotonic()
    deadline = None if timeout is None else started + timeout
    told = False
    while True:
        limit = within(deadline)
        proxy.limit(limit)
        try:
            if name in services(proxy):
                return
        except TimeoutExpired:
            if limit >= master_timeout():  # the master's own limit, not what was left of ours
                raise
        waited = time.monotonic() - started
        if timeout is not None and waited > timeout:
            raise TimeoutExpired(f"service {name} did not appear within {timeout:g} s")
        if timeout is None and not told and waited >= WAIT_NOTICE:
            _say_waiting(f"service {name} to appear")
            told = True
        time.sleep(0.1)


def _print(
    request: Renderer, response: Renderer, messages: tuple[Any, Any], verbose: bool, fmt: Format
) -> None:
    """The response (with ``verbose``, the request first), as rosservice prints it or as data."""
    asked, answered = messages
    if fmt is Format.text:
        shown = response.text(answered)
        output.line(request.text(asked) + "\n---\n" + shown if verbose else shown)
    else:
        data = response.plain(answered)
        if verbose:
            data = {"request": request.plain(asked), "response": data}
        if fmt is Format.json:
            from rostools.msgs.plain import dumps

            output.line(dumps(data))
        else:
            emit(fmt, data)
    output.flush()
