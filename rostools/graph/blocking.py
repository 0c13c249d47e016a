"""A blocking service client for commands: no node and no event loop needed.

``rosservice call`` is a one-shot: a socket with timeouts does it with less start-up than
asyncio. The protocol parts come from ``rostools.wire.tcpros``, as in ``graph.service``.
"""

from __future__ import annotations

import socket
import time
from urllib.parse import urlsplit

from rostools.errors import RostoolsError, ServiceError, TimeoutExpired, UnreachableError
from rostools.graph.masterapi import MasterProxy
from rostools.wire.tcpros import FrameError, ResponseReader, service_request_header


class BlockingServiceClient:
    """Probe or call one service."""

    def __init__(self, master: MasterProxy, name: str, timeout: float = 10.0) -> None:
        self.master = master
        self.name = name
        self.timeout = timeout

    def address(self) -> tuple[str, int]:
        """Host and port of the provider (NotFoundError when there is none)."""
        uri = self.master.lookup_service(self.name)
        parts = urlsplit(uri)
        if not parts.hostname or not parts.port:
            raise RostoolsError(f"the master gave {self.name} a bad URI: {uri}")
        return parts.hostname, parts.port

    def _exchange(
        self, header: bytes, request: bytes | None
    ) -> tuple[dict[str, str], bytes | None]:
        host, port = self.address()
        deadline = time.monotonic() + self.timeout
        try:
            sock = socket.create_connection((host, port), timeout=self.timeout)
        except OSError as err:
            raise UnreachableError(
                f"cannot connect to service {self.name} at {host}:{port}: {err.strerror or err}"
            ) from None
        reader = ResponseReader()
        sent_request = False
        try:
            sock.sendall(header)
            while True:
                sock.settimeout(max(deadline - time.monotonic(), 0.001))
                data = sock.recv(65536)
                if not data:
                    if reader.header is not None and "error" in reader.header:
                        break
                    what = "responding" if reader.header is not None else "answering"
                    raise RostoolsError(f"service {self.name} closed the connection without {what}")
                responses = reader.feed(data)
                fields = reader.header
                if fields is None:
                    continue
                if "error" in fields or request is None:
                    break
                if not sent_request:
                    # Only after the reply header: rospy drops bytes that come with the header.
                    sock.sendall(len(request).to_bytes(4, "little") + request)
                    sent_request = True
                if responses:
                    ok, payload = responses[0]
                    if not ok:
                        text = payload.decode("utf-8", "replace") or "(no reason given)"
                        raise ServiceError(f"service {self.name} failed: {text}")
                    return fields, payload
        except TimeoutError:
            raise TimeoutExpired(
                f"service {self.name} did not respond within {self.timeout:g} s"
            ) from None
        except FrameError as err:
            raise RostoolsError(f"garbage from service {self.name}: {err}") from None
        except OSError as err:
            raise RostoolsError(f"service {self.name}: {err.strerror or err}") from None
        finally:
            sock.close()
        assert reader.header is not None
        if "error" in reader.header:
            raise RostoolsError(f"service {self.name} refused the call: {reader.header['error']}")
        return reader.header, None

    def probe(self, caller_id: str) -> dict[str, str]:
        """The server's header: ``type`` and ``md5sum``."""
        header = service_request_header(caller_id, self.name, "*", probe=True)
        fields, _ = self._exchange(header, None)
        return fields

    def call(self, caller_id: str, md5sum: str, request: bytes) -> bytes:
        """One request; the response bytes."""
        header = service_request_header(caller_id, self.name, md5sum)
        _, payload = self._exchange(header, request)
        assert payload is not None
        return payload
