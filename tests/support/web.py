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
import signal
import subprocess
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any, ClassVar

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


def browser_missing(needs: str = "@foxglove/studio-base/assets/index.js") -> str | None:
    """Why chromium cannot run a page on ``node_modules/NEEDS`` (Studio's) here, or None."""
    if reason := node_missing():
        return reason
    if not Path(CHROMIUM).exists():
        return f"no chromium at {CHROMIUM} (scripts/install-ros1-peers.sh installs it)"
    if not (MODULES / needs).is_file():
        return f"tests/peers/web has no node_modules/{needs}: run npm ci there"
    return None


class NodeClient:
    """``foxglove-client.mjs``: the npm FoxgloveClient, driven by commands, read by events."""

    def __init__(self, url: str, subprotocol: str | None = None) -> None:
        self._start(["foxglove-client.mjs", url, *([subprotocol] if subprotocol else [])])

    def _start(self, args: list[str], env: dict[str, str] | None = None) -> None:
        """``node ARGS`` in ``tests/peers/web``, its stdin a pipe for commands."""
        self.proc = Proc(["node", *args], env=env, cwd=WEB, stdin=subprocess.PIPE)
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


def reap_browser(pidfile: Path) -> None:
    """Stop the chromium a driver wrote to ``pidfile``, if it is still there.

    puppeteer starts chromium in a session of its own, so a driver killed before it closed
    the browser (a timeout) left chromium running: one spun a core for an hour.
    """
    try:
        pid_text, profile = pidfile.read_text().splitlines()[:2]
        pid = int(pid_text)
        running = Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
    except (OSError, ValueError):
        return  # never written, or gone
    if profile and profile.encode() in running:  # that browser, not a PID used again
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(pid, signal.SIGKILL)  # its group: the browser and its helpers


class BrowserPage(NodeClient):
    """``page.mjs``: a page in Debian's chromium, driven by commands, read by events."""

    def __init__(self, url: str, shot: Path, home: Path) -> None:
        self.pidfile = home / "browser.pid"
        env = dict(os.environ, CHROMIUM=CHROMIUM, HOME=str(home), BROWSER_PIDFILE=str(self.pidfile))
        self._start(["page.mjs", url, str(shot)], env)
        try:
            self._answer("open", 60)
        except BaseException:
            self.stop()
            raise

    def said(self) -> list[dict[str, Any]]:
        """What the page said so far: console, uncaught errors, requests refused or failed."""
        kinds = ("console", "pageerror", "refused", "http")
        return [e for e in self.events if e["event"] in kinds]

    def frames(self, direction: str = "sent") -> list[str]:
        """The page's WebSocket frames so far, ``sent`` or ``received`` (500 characters each)."""
        return [e["data"] for e in self.events if e["event"] == "ws" and e["dir"] == direction]

    def _answer(self, kind: str, timeout: float) -> dict[str, Any]:
        event = self.expect(lambda e: e["event"] in (kind, "error"), timeout)
        if event["event"] == "error":
            raise AssertionError(f"{event['text']}; the page said {self.said()[-10:]}")
        return event

    def text(self, selector: str, match: str, timeout: float = 30.0) -> str:
        """``selector``'s text once it matches the regex ``match`` (JavaScript's, multiline)."""
        self.send(do="text", selector=selector, match=match, timeout=scaled(timeout))
        text: str = self._answer("text", timeout + 30)["text"]  # the page's own deadline first
        return text

    def click(self, selector: str) -> None:
        """Click the element ``selector`` names."""
        self.send(do="click", selector=selector)
        self._answer("clicked", 30)

    def stop(self) -> None:
        """Stop the driver, and its browser if the driver left it."""
        try:
            super().stop()
        finally:
            reap_browser(self.pidfile)

    def close(self) -> None:
        """Take the screenshot, close the browser, stop the driver (once: then nothing)."""
        if self.proc.popen.poll() is not None:
            self.stop()  # its pipes and its group, if not yet
            return
        try:
            self.send(do="close")
            self._answer("closed", 60)
        finally:
            self.stop()


@contextlib.contextmanager
def serve_web(pages: dict[str, str] | None = None) -> Iterator[str]:
    """``tests/peers/web`` and ``pages`` (path -> HTML) on a free loopback port: its base URL.

    ``pages`` is read at each request: a page may be added once the URL is known.
    """
    handler = functools.partial(_Quiet, directory=str(WEB), pages={} if pages is None else pages)
    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), handler)
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        yield f"http://127.0.0.1:{server.server_address[1]}/"
    finally:
        server.shutdown()
        server.server_close()


@contextlib.contextmanager
def studio_shell() -> Iterator[str]:
    """Foxglove Studio 1.48's shell, served on a free loopback port: its ``index.html`` URL."""
    with serve_web() as base:
        yield f"{base}studio.html"


class _Quiet(http.server.SimpleHTTPRequestHandler):
    # a module script served as anything but JavaScript is refused by the browser
    extensions_map: ClassVar[dict[str, str]] = {
        **http.server.SimpleHTTPRequestHandler.extensions_map,
        ".js": "text/javascript",
        ".mjs": "text/javascript",
    }

    def __init__(self, *args: Any, pages: dict[str, str], **kwargs: Any) -> None:
        self.pages = pages  # before the base class's __init__, which answers the request
        super().__init__(*args, **kwargs)

    def do_GET(self) -> None:
        """A page of ``pages``, or a file."""
        page = self.pages.get(self.path.partition("?")[0])
        if page is None:
            super().do_GET()
            return
        body = page.encode()
        self.send_response(200)
        self.send_header("Content-Type", "text/html; charset=utf-8")
        self.send_header("Content-Length", str(len(body)))
        self.end_headers()
        self.wfile.write(body)

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
    pidfile = out.parent / f"{out.stem}.browser.pid"
    env = dict(os.environ, CHROMIUM=CHROMIUM, HOME=str(out.parent), BROWSER_PIDFILE=str(pidfile))
    try:
        done = subprocess.run(
            ["node", str(WEB / "studio.mjs"), page, str(out), str(scaled(timeout)), *args],
            cwd=WEB, env=env, capture_output=True, text=True, timeout=scaled(timeout) + 60,
        )  # fmt: skip
    finally:
        reap_browser(pidfile)
    lines = [line for line in done.stdout.splitlines() if line.startswith("{")]
    assert lines, f"studio.mjs printed nothing: {done.stderr[-2000:]}"
    result: dict[str, Any] = json.loads(lines[-1])
    return result
