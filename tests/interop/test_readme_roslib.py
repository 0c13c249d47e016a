"""The README's roslib page, as written, in Debian's chromium against ``rostools bridge``.

The page is the README's ``html`` block whose marker names this file: if the page changes,
this test runs the new one. Two things change on the way to the browser, and nothing else:
each ``https://unpkg.com/PACKAGE@VERSION/PATH`` becomes the same file of the same version in
``tests/peers/web/node_modules`` (traffic stays on loopback), and the page's
``ws://127.0.0.1:8765`` becomes the test's bridge.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

from tests.support.docblocks import blocks
from tests.support.foxglove import start_bridge
from tests.support.procs import start_cli, subscribers, wait_for
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


def test_the_readme_roslib_page_hears_chatter_and_drives_cmd_vel(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    if reason := browser_missing("roslib/importmap.js"):
        pytest.skip(reason)
    page = readme_page()  # before anything starts: a README without it fails here
    talker = start_cli("topic", "pub", "-r", "10", "/chatter", "std_msgs/String", "data: hi",
                       env=cli_env)  # fmt: skip
    echo = start_cli("topic", "echo", "-n", "1", "/cmd_vel", "-F", "json", env=cli_env)
    bridge, url = start_bridge(cli_env)
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    shot = ARTIFACTS / "readme-roslib-page.png"
    browser: BrowserPage | None = None
    try:
        pages: dict[str, str] = {}
        with serve_web(pages) as base:
            pages["/teleop.html"] = served(page, base, url)
            browser = BrowserPage(f"{base}teleop.html", shot, tmp_path)
            log = browser.text("#log", r"^connected$")
            log = browser.text("#log", r"^topics: .*/chatter")
            log = browser.text("#log", r"^heard: hi$")
            # the click's one message goes to a subscriber already there
            wait_for(lambda: subscribers(rostools_master, "/cmd_vel"), 30, "echo on /cmd_vel")
            browser.click("#go")
            heard = json.loads(echo.expect(r"^\{", 30))
            log = browser.text("#log", r"heard: hi")  # the page still up, for its screenshot
            browser.close()
            said = browser.said()
    finally:
        if browser is not None:
            browser.stop()
        for proc in (echo, bridge, talker):
            proc.stop()
    assert heard["linear"] == {"x": 0.2, "y": 0.0, "z": 0.0}, heard
    assert heard["angular"] == {"x": 0.0, "y": 0.0, "z": 0.0}, heard
    topics = next(line for line in log.splitlines() if line.startswith("topics: "))
    assert "/chatter" in topics.split()[1:], topics
    assert not [e for e in said if e["event"] in ("pageerror", "refused")], said
    assert shot.stat().st_size > 0
