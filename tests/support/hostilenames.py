"""A hostile peer's names: line breaks and terminal escapes, registered with a master.

A peer may register any name the master takes: rosmaster refuses only ``:`` and spaces, so
a newline, NEL, the 8-bit CSI (``\\x9b``, a terminal escape) and U+2028 reach every command
through the master (XML 1.0 has no ESC, and turns a CR into a newline on the way). ESC and
CR reach us through a publisher's connection header and a bag file (``RAW``).
"""

from __future__ import annotations

import urllib.request
import xmlrpc.client
from typing import Any

from tests.support.env import run_cli
from tests.support.procs import free_port

#: What a peer can put in a name through the master, and how text output shows it.
NASTY = "\n\x85\x9b31m\u2028"
SHOWN = "\\n\\x85\\x9b31m\\u2028"
#: What a connection header or a bag can carry besides.
RAW = "\x1b[31m\r\n"
RAW_SHOWN = "\\x1b[31m\\r\\n"

NODE = "/evil" + NASTY
TOPIC = "/x" + NASTY + "/y"
TYPE = "pkg/T" + NASTY
SERVICE = "/srv" + NASTY
PARAM = "/p" + NASTY + "/q"
URDF = '<robot name="r">\n  <link name="base"/>\n</robot>\n'

#: Line breaks and terminal controls that must never reach a terminal raw.
CONTROLS = {chr(c) for c in (*range(0x20), *range(0x7F, 0xA0), 0x2028, 0x2029)} - {"\n", "\t"}


def call(master: str, method: str, *params: Any) -> Any:
    """A raw XML-RPC call, as a hostile peer would make it; the ROS triple's value."""
    body = xmlrpc.client.dumps(params, method).encode()
    request = urllib.request.Request(master, body, {"Content-Type": "text/xml"})
    with urllib.request.urlopen(request, timeout=10) as answer:
        code, message, value = xmlrpc.client.loads(answer.read())[0][0]
    assert code == 1, message
    return value


def register(master: str) -> str:
    """A node named with line breaks publishes such topics, of such a type, at such a URI.

    ``/legal`` subscribes one, offers such a service and sets such a parameter (and
    ``/urdf``, a value with line breaks of its own). Nothing listens at either URI, so
    whoever connects is refused. Returns that URI.
    """
    dead = f"http://127.0.0.1:{free_port()}/{NASTY}"
    call(master, "registerPublisher", NODE, TOPIC, TYPE, dead)
    call(master, "registerPublisher", NODE, "/plain", TYPE, dead)
    call(master, "registerSubscriber", "/legal", TOPIC, TYPE, dead)
    service_uri = f"rosrpc://127.0.0.1:{free_port()}"
    call(master, "registerService", "/legal", SERVICE, service_uri, dead)
    call(master, "setParam", "/legal", PARAM, "value")
    call(master, "setParam", "/legal", "/urdf", URDF)
    return dead


def shown(text: str) -> str:
    """``text`` as text output shows it."""
    return text.replace(NASTY, SHOWN)


def clean_lines(text: str) -> list[str]:
    """``text``'s lines, after checking that none holds a raw control character."""
    raw = sorted({repr(c) for c in text if c in CONTROLS})
    assert not raw, f"raw {', '.join(raw)} in:\n{text!r}"
    return text.splitlines()


def cli(env: dict[str, str], *args: str, code: int = 0) -> tuple[list[str], list[str]]:
    """Run a command; its stdout and stderr lines, each checked for raw control characters."""
    done = run_cli(*args, env=env, timeout=60)
    assert done.returncode == code, (args, done.returncode, done.stderr)
    return clean_lines(done.stdout), clean_lines(done.stderr)
