"""The browser harness stops the chromium it started, even when its driver is killed first.

puppeteer starts chromium in a session of its own, so stopping the node driver's process
group left the browser running (one spun a core for an hour after a driver's timeout).
"""

from __future__ import annotations

import os
import signal
from pathlib import Path

import pytest

from tests.support.procs import wait_for
from tests.support.web import BrowserPage, browser_missing, serve_web

pytestmark = [pytest.mark.interop]


def test_a_browser_whose_driver_was_killed_is_stopped(tmp_path: Path) -> None:
    if reason := browser_missing("puppeteer-core/package.json"):
        pytest.skip(reason)
    with serve_web({"/plain.html": "<!doctype html><p id='p'>here</p>"}) as site:
        page = BrowserPage(f"{site}plain.html", tmp_path / "plain.png", tmp_path)
        try:
            assert page.text("#p", "here") == "here"
            browser = int(page.pidfile.read_text().split()[0])
            os.killpg(page.proc.popen.pid, signal.SIGKILL)  # the driver, as a timeout kills it
            page.proc.popen.wait(30)
            assert Path(f"/proc/{browser}").exists()  # left running: what the harness must stop
        finally:
            page.stop()
        wait_for(lambda: not Path(f"/proc/{browser}").exists(), 15, "chromium to be stopped")
