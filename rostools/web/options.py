"""What ``rostools bridge`` and ``rostools.bridge()`` take."""

from __future__ import annotations

import ssl
from dataclasses import dataclass, field

from rostools.errors import UsageError
from rostools.selection import TopicChoice

#: Foxglove's port, as foxglove_bridge and Studio's default connection use it.
DEFAULT_PORT = 8765
LOOPBACK = ("127.0.0.1", "::1", "localhost")
#: What ``--protocol`` takes.
PROTOCOLS = ("both", "foxglove", "rosbridge")


@dataclass
class BridgeOptions(TopicChoice):
    """The topics to offer (no choice: every topic), where to listen, and what to allow."""

    address: str = "127.0.0.1"
    port: int = DEFAULT_PORT
    #: A shared secret a client gives as ``?token=`` in its URL; "" lets anyone connect.
    token: str = ""
    certfile: str | None = None
    keyfile: str | None = None
    #: topic -> the most messages a second any client is sent of it
    max_rates: dict[str, float] = field(default_factory=dict)
    #: Refuse what writes to the graph: client publish, setParameters, service calls.
    read_only: bool = False
    #: What clients may speak: "foxglove", "rosbridge" (v2), or "both" (by the subprotocol
    #: a client offers).
    protocol: str = "both"

    def __post_init__(self) -> None:
        """No topic chosen means every topic, as foxglove_bridge's default."""
        if not (self.topics or self.all or self.node or self.types):
            self.all = True
        if self.protocol not in PROTOCOLS:
            raise UsageError(f"--protocol {self.protocol}: choose one of {', '.join(PROTOCOLS)}")

    @property
    def loopback(self) -> bool:
        """Whether only this machine can connect."""
        return self.address in LOOPBACK or self.address.startswith("127.")

    def tls(self) -> ssl.SSLContext | None:
        """The TLS context for ``wss://``, or None for ``ws://``."""
        if not self.certfile:
            if self.keyfile:
                raise UsageError("--keyfile needs --certfile")
            return None
        context = ssl.SSLContext(ssl.PROTOCOL_TLS_SERVER)
        try:
            context.load_cert_chain(self.certfile, self.keyfile)
        except (OSError, ssl.SSLError) as err:
            raise UsageError(f"cannot use the certificate {self.certfile}: {err}") from err
        return context


def parse_rate(text: str) -> tuple[str, float]:
    """``TOPIC=HZ`` as a topic and a positive rate."""
    topic, sep, rate = text.rpartition("=")
    try:
        hz = float(rate)
    except ValueError:
        hz = 0.0
    if not sep or not topic or not hz > 0 or hz == float("inf"):
        raise UsageError(f"--max-rate {text}: give TOPIC=HZ, with HZ a positive number")
    return topic, hz
