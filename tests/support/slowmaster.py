"""A proxy in front of a master that delays the calls a test names: a slow master, made to order.

Clients use the proxy's URI as ``ROS_MASTER_URI``. Every request goes on to the real master,
even one whose client has given up waiting, as a busy rosmaster still carries out a call its
caller no longer waits for. ``delay(method, seconds, only=TEXT)`` delays the calls of
``method`` whose body holds ``TEXT`` (a topic name, say); ``delayed`` counts them, so a test
can show the delay took place.
"""

from __future__ import annotations

import http.client
import re
import threading
from collections import Counter
from collections.abc import Iterator
from contextlib import contextmanager
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from urllib.parse import urlsplit

#: A call's method, or each method of a ``system.multicall``.
_METHOD = re.compile(
    rb"<methodName>\s*([^<\s]+)\s*</methodName>"
    rb"|<name>methodName</name>\s*<value>\s*(?:<string>)?\s*([^<\s]+)"
)


class SlowMaster:
    """The proxy's state: what to delay, and what was delayed."""

    def __init__(self, master_uri: str) -> None:
        parts = urlsplit(master_uri)
        self.host, self.port = parts.hostname or "127.0.0.1", parts.port or 11311
        #: method -> (seconds, text the body must hold, or None for every call)
        self.delays: dict[str, tuple[float, bytes | None]] = {}
        #: How many calls of each method were delayed.
        self.delayed: Counter[str] = Counter()
        self.lock = threading.Lock()
        self.uri = ""
        #: Set when the proxy stops: a call still held back then is dropped, not forwarded.
        self.closed = threading.Event()

    def delay(self, method: str, seconds: float, only: str | None = None) -> None:
        """Delay ``method`` (the calls whose body holds ``only``) by ``seconds`` from now on."""
        with self.lock:
            self.delays[method] = (seconds, None if only is None else only.encode())

    def wait_before(self, body: bytes) -> float:
        """How long to hold this request back (and count each delayed call in it).

        A ``system.multicall`` is as slow as the slowest call it holds, as on a busy master.
        """
        wait = 0.0
        with self.lock:
            for found in _METHOD.finditer(body):
                method = (found.group(1) or found.group(2)).decode()
                seconds, only = self.delays.get(method, (0.0, None))
                if seconds > 0 and (only is None or only in body):
                    self.delayed[method] += 1
                    wait = max(wait, seconds)
        return wait

    def forward(self, body: bytes) -> tuple[int, bytes]:
        """The real master's answer to one request."""
        conn = http.client.HTTPConnection(self.host, self.port, timeout=120)
        try:
            conn.request("POST", "/RPC2", body, {"Content-Type": "text/xml"})
            response = conn.getresponse()
            return response.status, response.read()
        finally:
            conn.close()


def _handler(state: SlowMaster) -> type[BaseHTTPRequestHandler]:
    class Handler(BaseHTTPRequestHandler):
        protocol_version = "HTTP/1.1"

        def do_POST(self) -> None:
            body = self.rfile.read(int(self.headers.get("Content-Length", "0")))
            state.closed.wait(state.wait_before(body))
            self.close_connection = True
            if state.closed.is_set():
                return  # the test is over, and its master may be gone
            try:
                status, answer = state.forward(body)
            except OSError:
                # the master went first: the client sees a dropped call, not the proxy's
                # traceback (a thread printing one while pytest parses, as the import test
                # does, trips a CPython 3.11 race: "AST constructor recursion depth mismatch")
                return
            self.close_connection = False
            try:
                self.send_response(status)
                self.send_header("Content-Type", "text/xml")
                self.send_header("Content-Length", str(len(answer)))
                self.end_headers()
                self.wfile.write(answer)
            except OSError:
                self.close_connection = True  # the client gave up waiting: the call was made

        def log_message(self, format: str, *args: object) -> None:
            """Quiet: the test says what matters."""

    return Handler


@contextmanager
def slow_master(master_uri: str) -> Iterator[SlowMaster]:
    """A proxy of ``master_uri`` on a free loopback port, while in the ``with``."""
    state = SlowMaster(master_uri)
    server = ThreadingHTTPServer(("127.0.0.1", 0), _handler(state))
    server.daemon_threads = True
    state.uri = f"http://127.0.0.1:{server.server_address[1]}/"
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield state
    finally:
        state.closed.set()
        server.shutdown()
        server.server_close()
        thread.join(5)
