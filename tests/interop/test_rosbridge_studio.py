"""Foxglove Studio 1.48's Rosbridge data source in Debian's chromium, against each server in
``SERVERS``: the real rosbridge_server 0.11.17 first, then ``rostools bridge``, both on a
``rosmaster --core`` with ``rosbridge_graph.py``.

Studio's Rosbridge source (``RosbridgePlayer``, on Foxglove's roslibjs fork) lists the topics
it gets from ``/rosapi/topics_and_raw_types`` (types and full message definitions), maps the
graph with ``/rosapi/nodes`` and ``/rosapi/node_details``, and subscribes with ``cbor-raw``,
decoding the TCPROS bytes itself. The page's WebSocket frames are kept beside the screenshot
in ``build/test-artifacts`` (``rosbridge-studio-KIND.frames.jsonl``): what Studio asked and
what it was answered.
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from tests.support.env import ros1_missing
from tests.support.foxglove import start_bridge
from tests.support.rosbridge import (
    rosbridge_graph,
    rosbridge_missing,
    start_rosbridge,
    start_rosmaster,
)
from tests.support.web import browser_missing, read_frames, run_studio, studio_shell

pytestmark = [pytest.mark.interop]

ARTIFACTS = Path(__file__).resolve().parent.parent.parent / "build" / "test-artifacts"

#: The servers Studio connects to: rosbridge_server first, so a failure of ours can be told
#: from a failure of the harness.
SERVERS = ["rosbridge_server", "rostools"]

#: The graph's topics (``rosbridge_graph.py``) as Studio's Topics list shows them.
GRAPH_TOPICS = ["/chatter\nstd_msgs/String", "/from_web_echo\nstd_msgs/String",
                "/from_web\nstd_msgs/String"]  # fmt: skip


@dataclass
class Server:
    """A rosbridge v2 server on a graph of ``rosbridge_graph.py``."""

    kind: str
    url: str


@pytest.fixture(params=SERVERS)
def server(
    request: pytest.FixtureRequest, tmp_path: Path, cli_env: dict[str, str]
) -> Iterator[Server]:
    """The server ``request.param`` on a fresh ``rosmaster --core`` with the test graph (and,
    for rostools, no rosapi_node: its rosapi answers are its own)."""
    if reason := browser_missing():
        pytest.skip(reason)
    real = request.param == "rosbridge_server"
    if reason := (rosbridge_missing() if real else ros1_missing()):
        pytest.skip(reason)
    master, uri = start_rosmaster(tmp_path)
    try:
        with rosbridge_graph(uri, tmp_path):
            if real:
                bridge = start_rosbridge(uri, tmp_path)
                try:
                    yield Server(request.param, bridge.url)
                finally:
                    bridge.stop()
            else:
                cli_env["ROS_MASTER_URI"] = uri
                proc, url = start_bridge(cli_env, "-a")
                try:
                    yield Server(request.param, url)
                finally:
                    proc.stop()
    finally:
        master.stop()


def answered(frames: list[dict[str, Any]]) -> dict[str, list[dict[str, Any]]]:
    """Each rosapi service Studio called: the answers it got (by the call's ``id``)."""
    sent = [f["json"] for f in frames if f["dir"] == "sent" and "json" in f]
    got = {
        f["json"].get("id"): f["json"]
        for f in frames
        if f["dir"] == "received" and f.get("json", {}).get("op") == "service_response"
    }
    calls: dict[str, list[dict[str, Any]]] = {}
    for op in sent:
        if op.get("op") == "call_service":
            calls.setdefault(op["service"], []).append(got.get(op.get("id"), {}))
    return calls


def test_studio_rosbridge_source_lists_topics_and_shows_a_message(server: Server) -> None:
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    shot = ARTIFACTS / f"rosbridge-studio-{server.kind}.png"
    log = ARTIFACTS / f"rosbridge-studio-{server.kind}.frames.jsonl"
    with studio_shell() as page:
        seen = run_studio(
            f"{page}?ds=rosbridge-websocket&ds.url={server.url}", shot,
            *[a for t in GRAPH_TOPICS for a in ("--topic", t.split("\n")[0])],
            "--text", r"hello \d+", "--no-rate", "--frames", str(log), timeout=120,
        )  # fmt: skip
    frames = read_frames(log)
    assert "error" not in seen, f"{seen}; see {shot} and {log}"
    for topic in GRAPH_TOPICS:  # each with its type, from /rosapi/topics_and_raw_types
        assert topic in seen["topics"], seen["topics"]
    assert re.fullmatch(r"hello \d+", seen["raw"])  # the Raw Messages panel shows /chatter

    calls = answered(frames)
    assert "/rosapi/topics_and_raw_types" in calls, sorted(calls)
    for service, answers in calls.items():
        assert answers[0], f"{service}: no answer"  # later ones may be cut off by the close
        for answer in filter(None, answers):
            assert answer["result"] is True, f"{service}: {answer}"
    complaints = [
        f["json"] for f in frames if f["dir"] == "received"
        and f.get("json", {}).get("op") == "status" and f["json"].get("level") != "info"
    ]  # fmt: skip
    assert not complaints, complaints
    topics = calls["/rosapi/topics_and_raw_types"][0]
    values = topics["values"]
    definitions = dict(zip(values["topics"], values["typedefs_full_text"], strict=True))
    assert definitions["/chatter"].strip() == "string data"
    subscribes = [
        f["json"] for f in frames if f.get("json", {}).get("op") == "subscribe"
        and f["dir"] == "sent" and f["json"]["topic"] == "/chatter"
    ]  # fmt: skip
    assert subscribes and subscribes[0]["compression"] == "cbor-raw", subscribes
    assert any(f["dir"] == "received" and "binary" in f for f in frames), "no cbor-raw message"
