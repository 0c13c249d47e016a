"""The JavaScript and browser peers of the bridge tests: where they are, and how to drive them.

They live in ``tests/peers/web`` (pinned by its ``package-lock.json``, installed by ``npm ci``
from ``scripts/install-ros1-peers.sh``), with Debian's ``node`` and ``chromium``. A missing
one is a skip with its reason, which ``CI=true`` turns into a failure.
"""

from __future__ import annotations

import contextlib
import functools
import http.server
import json
import os
import shutil
import subprocess
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from tests.support.load import scaled
from tests.support.procs import Proc

WEB = Path(__file__).resolve().parent.parent / "peers" / "web"
MODULES = WEB / "node_modules"
CHROMIUM = os.environ.get("CHROMIUM", "/usr/bin/chromium")


def node_missing() -> str | None:
    """Why the Node peers cannot run here, or None."""
    if shutil.which("node") is None:
        return "node is not installed (scripts/install-ros1-peers.sh installs it)"
    if not (MODULES / "@foxglove" / "ws-protocol").is_dir():
        return "tests/peers/web has no node_modules: run npm ci there (the install script does)"
    return None


def browser_missing() -> str | None:
    """Why the browser peer cannot run here, or None."""
    if reason := node_missing():
        return reason
    if not Path(CHROMIUM).exists():
        return f"no chromium at {CHROMIUM} (scripts/install-ros1-peers.sh installs it)"
    if not (MODULES / "@foxglove" / "studio-base" / "assets" / "index.js").is_file():
        return "@foxglove/studio-base is not installed in tests/peers/web"
    return None


class NodeClient:
    """``foxglove-client.mjs``: the npm FoxgloveClient, driven by commands, read by events."""

    def __init__(self, url: str, subprotocol: str | None = None) -> None:
        argv = [
            "node",
            str(WEB / "foxglove-client.mjs"),
            url,
            *([subprotocol] if subprotocol else []),
        ]
        self.proc = Proc(argv, cwd=WEB, stdin=subprocess.PIPE)
        #: Every event, and those no ``expect`` has taken yet.
        self.events: list[dict[str, Any]] = []
        self.pending: list[dict[str, Any]] = []

    def send(self, **command: Any) -> None:
        """One command (``do=...``)."""
        stdin = self.proc.popen.stdin
        assert stdin is not None
        stdin.write((json.dumps(command) + "\n").encode())
        stdin.flush()

    def expect(
        self, match: Callable[[dict[str, Any]], bool], timeout: float = 15.0
    ) -> dict[str, Any]:
        """The first event not yet taken that ``match``es (events come in any order)."""
        deadline = time.monotonic() + scaled(timeout)
        while True:
            for n, event in enumerate(self.pending):
                if match(event):
                    del self.pending[n]
                    return event
            left = deadline - time.monotonic()
            if left <= 0:
                raise AssertionError(
                    f"no such event from the node client; last: {self.events[-5:]}"
                )
            try:
                line = self.proc.expect(r"^\{", left)
            except AssertionError:
                continue  # out of time: said above, with the last events
            event = json.loads(line)
            self.events.append(event)
            self.pending.append(event)

    def stop(self) -> None:
        """Stop the client's process."""
        self.proc.stop()


@contextlib.contextmanager
def studio_shell() -> Iterator[str]:
    """Foxglove Studio 1.48's shell, served on a free loopback port: its ``index.html`` URL."""
    handler = functools.partial(_Quiet, directory=str(WEB))
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}/studio.html"
    finally:
        server.shutdown()
        server.server_close()


class _Quiet(http.server.SimpleHTTPRequestHandler):
    def log_message(self, format: str, *args: Any) -> None:
        """Say nothing for each request."""


def read_frames(path: Path) -> list[dict[str, Any]]:
    """``studio.mjs --frames``'s file: each WebSocket frame, a text frame's JSON as ``json``."""
    frames = []
    for line in path.read_text().splitlines():
        frame = json.loads(line)
        if "text" in frame:
            with contextlib.suppress(ValueError):
                frame["json"] = json.loads(frame["text"])
        frames.append(frame)
    return frames


def run_studio(page: str, out: Path, *args: str, timeout: float = 90.0) -> dict[str, Any]:
    """``studio.mjs PAGE OUT ARGS``: what Studio showed, as the driver prints it."""
    env = dict(os.environ, CHROMIUM=CHROMIUM, HOME=str(out.parent))
    done = subprocess.run(
        ["node", str(WEB / "studio.mjs"), page, str(out), str(scaled(timeout)), *args],
        cwd=WEB, env=env, capture_output=True, text=True, timeout=scaled(timeout) + 60,
    )  # fmt: skip
    lines = [line for line in done.stdout.splitlines() if line.startswith("{")]
    assert lines, f"studio.mjs printed nothing: {done.stderr[-2000:]}"
    result: dict[str, Any] = json.loads(lines[-1])
    return result
