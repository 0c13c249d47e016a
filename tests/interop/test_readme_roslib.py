"""The README's roslib page, as written, in Debian's chromium against ``rostools bridge``,
and against the real rosbridge_server 0.11.17 (what the page must do there, it must do here).

The page is the README's ``html`` block whose marker names this file: if the page changes,
this test runs the new one. Two things change on the way to the browser, and nothing else:
each ``https://unpkg.com/PACKAGE@VERSION/PATH`` becomes the same file of the same version in
``tests/peers/web/node_modules`` (traffic stays on loopback), and the page's
``ws://127.0.0.1:8765`` becomes the test's bridge.
"""

from __future__ import annotations

import json
import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

import rostools
from tests.support.docblocks import blocks
from tests.support.foxglove import start_bridge
from tests.support.load import scaled
from tests.support.procs import free_port, start_cli, start_rostools_core
from tests.support.rosbridge import rosbridge_missing, start_rosbridge, start_rosmaster
from tests.support.web import MODULES, BrowserPage, browser_missing, serve_web

pytestmark = pytest.mark.interop

ROOT = Path(__file__).resolve().parent.parent.parent
ARTIFACTS = ROOT / "build" / "test-artifacts"
UNPKG = re.compile(r"https://unpkg\.com/((?:@[^/@]+/)?[^/@]+)@([^/]+)/([^\"'\s]+)")
README_URL = "ws://127.0.0.1:8765"


def readme_page() -> str:
    """The README's page that names this test in its marker."""
    pages = [
        b
        for b in blocks(ROOT / "README.md")
        if b.lang == "html" and Path(__file__).name in b.markers.get("not run", "")
    ]
    assert len(pages) == 1, f"README.md has {len(pages)} html blocks naming {Path(__file__).name}"
    return pages[0].body


def served(page: str, base: str, bridge_url: str) -> str:
    """``page`` on loopback: each unpkg file from ``base``'s node_modules, the test's bridge.

    A file is served only if node_modules has the very version the page names.
    """

    def local(url: re.Match[str]) -> str:
        package, version, path = url.groups()
        installed = json.loads((MODULES / package / "package.json").read_text())["version"]
        assert installed == version, f"the page loads {package}@{version}, npm ci has {installed}"
        assert (MODULES / package / path).is_file(), f"{package}@{version} has no {path}"
        return f"{base}node_modules/{package}/{path}"

    page, loaded = UNPKG.subn(local, page)
    assert loaded, "the README's page no longer loads roslib from unpkg"
    assert page.count(README_URL) == 1, f"the README's page no longer connects to {README_URL}"
    page = page.replace(README_URL, bridge_url)
    assert "https://" not in page, "the README's page loads something else from the internet"
    return page


@dataclass
class Server:
    """A rosbridge v2 server on a master: the master's URI and the server's URL."""

    kind: str
    master_uri: str
    url: str


@pytest.fixture(params=["rostools", "rosbridge_server"])
def server(
    request: pytest.FixtureRequest, cli_env: dict[str, str], tmp_path: Path
) -> Iterator[Server]:
    """``rostools bridge`` on ``rostools core``, or the real rosbridge_server on ``rosmaster``.

    ``cli_env`` points at the master.
    """
    if reason := browser_missing("roslib/importmap.js"):
        pytest.skip(reason)
    if request.param == "rostools":
        port = free_port()
        cli_env["ROS_MASTER_URI"] = uri = f"http://127.0.0.1:{port}"
        master = start_rostools_core(port, cli_env)
        try:
            bridge, url = start_bridge(cli_env)
            try:
                yield Server(request.param, uri, url)
            finally:
                bridge.stop()
        finally:
            master.stop()
        return
    if reason := rosbridge_missing():
        pytest.skip(reason)
    master, uri = start_rosmaster(tmp_path)
    cli_env["ROS_MASTER_URI"] = uri
    try:
        real = start_rosbridge(uri, tmp_path)
        try:
            yield Server(request.param, uri, real.url)
        finally:
            real.stop()
    finally:
        master.stop()


def test_the_readme_roslib_page_hears_chatter_and_drives_cmd_vel(
    server: Server, cli_env: dict[str, str], tmp_path: Path
) -> None:
    page = readme_page()  # before anything starts: a README without it fails here
    talker = start_cli("topic", "pub", "-r", "10", "/chatter", "std_msgs/String", "data: hi",
                       env=cli_env)  # fmt: skip
    # a robot's base, say: on /cmd_vel before the page is, as the page's one message must find
    base_node = rostools.Node("base", server.master_uri)
    cmd_vel = base_node.subscribe("/cmd_vel", msg_type="geometry_msgs/Twist")
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    shot = ARTIFACTS / f"readme-roslib-page-{server.kind}.png"
    browser: BrowserPage | None = None
    try:
        pages: dict[str, str] = {}
        with serve_web(pages) as site:
            pages["/teleop.html"] = served(page, site, server.url)
            browser = BrowserPage(f"{site}teleop.html", shot, tmp_path)
            browser.text("#log", r"^connected$")
            browser.text("#log", r"^topics: .*/chatter")
            log = browser.text("#log", r"^heard: hi$")
            browser.click("#go")  # one click, one message
            try:
                heard = cmd_vel.get(timeout=scaled(30))
            except rostools.TimeoutExpired:
                sent = [f for f in browser.frames() if '"/chatter"' not in f]
                got = [f for f in browser.frames("received") if '"/chatter"' not in f]
                raise AssertionError(
                    f"/cmd_vel got nothing; the page sent {sent} and received {got}"
                ) from None
            browser.close()  # after the message: the page's screenshot, its bridge client gone
            said = browser.said()
    finally:
        if browser is not None:
            browser.close()  # if not yet: the screenshot of a failure
        base_node.close()
        talker.stop()
    assert (heard.linear.x, heard.linear.y, heard.linear.z) == (0.2, 0.0, 0.0), heard
    assert (heard.angular.x, heard.angular.y, heard.angular.z) == (0.0, 0.0, 0.0), heard
    topics = next(line for line in log.splitlines() if line.startswith("topics: "))
    assert "/chatter" in topics.split()[1:], topics
    assert not [e for e in said if e["event"] in ("pageerror", "refused")], said
    assert shot.stat().st_size > 0
