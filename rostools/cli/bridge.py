"""``rostools bridge``: the live graph for Foxglove Studio, Lichtblick and the browser."""

from __future__ import annotations

import sys
import time
from functools import partial
from typing import TYPE_CHECKING, Annotated, Any, NamedTuple

import typer

from rostools.cli import output
from rostools.cli.common import FormatOpt, node_session, output_format
from rostools.cli.declare import command
from rostools.cli.liveview import LiveView
from rostools.cli.output import Format
from rostools.cli.register import add
from rostools.errors import one_line

if TYPE_CHECKING:
    import asyncio

    from rostools.node.node import LiveNode
    from rostools.web.options import BridgeOptions
    from rostools.web.server import Bridge

app = typer.Typer(
    name="bridge",
    help="Serve the live graph over WebSocket to Foxglove Studio, Lichtblick and browsers.",
    add_completion=False,
)


@command()
def bridge(
    ctx: typer.Context,
    topics: Annotated[
        list[str] | None, typer.Argument(help="Topics to offer (regexes with -e); none: all.")
    ] = None,
    all_topics: Annotated[bool, typer.Option("--all", "-a", help="Offer every topic.")] = False,
    regex: Annotated[bool, typer.Option("--regex", "-e", help="TOPICS are regexes.")] = False,
    exclude: Annotated[
        list[str] | None, typer.Option("--exclude", "-x", help="Leave out topics matching REGEX.")
    ] = None,
    port: Annotated[
        int, typer.Option("--port", "-p", min=0, max=65535, help="Port; 0 picks a free one.")
    ] = 8765,
    address: Annotated[
        str,
        typer.Option(
            "--address", help="Address to listen on; 0.0.0.0 lets other machines connect."
        ),
    ] = "127.0.0.1",
    token: Annotated[
        str | None,
        typer.Option(
            "--token",
            envvar="ROSTOOLS_BRIDGE_TOKEN",
            help="A secret each client must give in its URL (?token=...).",
        ),
    ] = None,
    certfile: Annotated[
        str | None, typer.Option("--certfile", help="TLS certificate (PEM): serve wss://.")
    ] = None,
    keyfile: Annotated[
        str | None, typer.Option("--keyfile", help="The certificate's private key (PEM).")
    ] = None,
    max_rate: Annotated[
        list[str] | None,
        typer.Option("--max-rate", help="TOPIC=HZ: send a topic at most this often."),
    ] = None,
    read_only: Annotated[
        bool,
        typer.Option(
            "--read-only", help="Refuse client publish, parameter changes and service calls."
        ),
    ] = False,
    protocol: Annotated[
        str,
        typer.Option(
            "--protocol",
            help="both: Foxglove to clients that offer its subprotocol, rosbridge v2 to the "
            "rest; or foxglove, or rosbridge, alone.",
        ),
    ] = "both",
    quiet: Annotated[bool, typer.Option("--quiet", "-q", help="No live table.")] = False,
    fmt: FormatOpt = None,
) -> None:
    """Serve the graph over WebSocket, in the Foxglove protocol and rosbridge v2, until Ctrl-C.

    Open Foxglove Studio or Lichtblick, choose "Foxglove WebSocket", and give the URL this
    prints; roslib, roslibpy and rosbridge dashboards take the same URL. Every topic's type
    comes from its publisher: no .msg files are needed.
    """
    from rostools.web.options import BridgeOptions, parse_rate

    fmt = output_format(ctx, fmt)
    opts = BridgeOptions(
        topics=list(topics or []),
        all=all_topics,
        regex=regex,
        exclude=list(exclude or []),
        address=address,
        port=port,
        token=token or "",
        certfile=certfile,
        keyfile=keyfile,
        max_rates=dict(parse_rate(r) for r in max_rate or []),
        read_only=read_only,
        protocol=protocol,
    )
    opts.tls()  # a certificate that does not load is a usage error before anything starts
    live = not quiet and fmt is Format.text and sys.stderr.isatty()
    node_session(ctx, partial(_run, opts, fmt, live, quiet), "rostools_bridge", fmt)


async def _run(
    opts: BridgeOptions, fmt: Format, live: bool, quiet: bool, node: LiveNode, stop: asyncio.Event
) -> None:
    import asyncio

    from rostools.msgs.store import TypeStore
    from rostools.web.server import Bridge

    def on_event(event: dict[str, Any]) -> None:
        if fmt is not Format.text:
            output.write(fmt, event)
        elif not live and not quiet and event["event"] in _SAID:
            sys.stderr.write(_SAID[event["event"]](event) + "\n")
            sys.stderr.flush()

    bridge = Bridge(node, opts, TypeStore.default(), on_event)

    def ready(b: Bridge) -> None:
        if fmt is Format.text:
            output.line(_banner(b), flush=True)
        if not opts.loopback:
            warning = (
                f"rostools bridge: listening on {opts.address}: anyone who reaches it can read "
                "the graph"
                + (", publish and call services" if not opts.read_only else "")
                + ("" if opts.token else "; give --token")
                + ("" if opts.certfile else " and --certfile for wss://")
            )
            sys.stderr.write(one_line(warning) + "\n")
            sys.stderr.flush()

    if not live:
        await bridge.run(stop, ready)
        return
    with BridgeTable() as table:
        drawing = asyncio.get_running_loop().create_task(table.follow(bridge, stop))
        try:
            await bridge.run(stop, ready)
        finally:
            drawing.cancel()
            table.draw(bridge)


def _banner(b: Bridge) -> str:
    url = b.url + ("/?token=…" if b.opts.token else "")
    where = "this machine only" if b.opts.loopback else f"{b.opts.address}, every machine"
    speaks = {"both": "Foxglove WebSocket and rosbridge v2", "foxglove": "Foxglove WebSocket",
              "rosbridge": "rosbridge v2"}[b.opts.protocol]  # fmt: skip
    lines = [f"rostools bridge: {url} ({speaks}; listening on {where})"]
    if b.opts.protocol != "rosbridge":
        lines.append(f"Foxglove or Lichtblick: open a connection, Foxglove WebSocket, {url}")
    if b.opts.protocol != "foxglove":
        lines.append(f"roslib, roslibpy: new ROSLIB.Ros({{url: '{url}'}})")
    return "\n".join([*lines, "press Ctrl-C to stop"])


_SAID = {
    "connected": lambda e: f"client {e['client']} connected ({e['protocol']})",
    "disconnected": lambda e: (
        f"client {e['client']} left: {e['messages']} messages sent, {e['dropped']} dropped"
    ),
    "refused": lambda e: one_line(f"client {e['client']}: refused: {e['reason']}"),
}


class _Sent(NamedTuple):
    """What a subscription was sent, as the live view counts it."""

    messages: int
    bytes: int


class BridgeTable(LiveView):
    """The live table on stderr: each client's subscriptions, rates, bytes and drops."""

    async def follow(self, bridge: Bridge, stop: asyncio.Event) -> None:
        """Redraw twice a second until ``stop``."""
        import asyncio

        while not stop.is_set():
            self.draw(bridge)
            await asyncio.sleep(0.5)

    def draw(self, bridge: Bridge) -> None:
        """Draw the table now."""
        from rich.markup import escape
        from rich.table import Table

        now = time.monotonic()
        where = bridge.url if bridge.port else "starting"
        title = (
            f"bridge {where}: {len(bridge.clients)} clients, "
            f"{len(bridge.channels)} topics, {now - bridge.started:.0f} s"
        )
        table = Table(title=title, title_justify="left")
        for col in ("client", "topic", "sent", "rate", "bandwidth", "throttled", "drops"):
            table.add_column(col, justify="left" if col in ("client", "topic") else "right")
        rows = [
            (f"{client.name} {sub.id}", client, sub)
            for client in sorted(bridge.clients, key=lambda c: c.name)
            for sub in client.subscriptions.values()
        ]
        self.measure(
            {k: _Sent(sub.sent, sub.sent_bytes) for k, _, sub in rows}, bridge.started, now
        )
        for key, client, sub in rows:
            hz, bw = self.rates.get(key, (0.0, 0.0))
            drops = f"[bold red]{sub.dropped}[/]" if sub.dropped else "0"
            table.add_row(
                escape(client.name),
                escape(one_line(sub.topic)),
                str(sub.sent),
                f"{hz:.1f} Hz",
                f"{bw / 1e6:.2f} MB/s",
                str(sub.throttled),
                drops,
            )
        self.live.update(table, refresh=True)


add(app, bridge)
