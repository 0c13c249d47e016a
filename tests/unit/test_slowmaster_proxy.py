"""The slow-master proxy of the tests (tests/support/slowmaster.py) fails quietly."""

from __future__ import annotations

import http.client

import pytest

from tests.support.procs import free_port
from tests.support.slowmaster import slow_master


def test_a_call_after_the_master_went_is_dropped_without_a_traceback(
    capfd: pytest.CaptureFixture[str],
) -> None:
    # It printed a traceback from its thread, which in a pytest worker can trip a CPython
    # 3.11 race with a test that parses source at that moment.
    gone = f"http://127.0.0.1:{free_port()}/"  # nothing listens there
    with slow_master(gone) as proxy:
        port = int(proxy.uri.rsplit(":", 1)[1].strip("/"))
        conn = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
        conn.request("POST", "/RPC2", b"<methodCall/>", {"Content-Type": "text/xml"})
        with pytest.raises(http.client.RemoteDisconnected):
            conn.getresponse()
        conn.close()
    assert capfd.readouterr().err == ""
