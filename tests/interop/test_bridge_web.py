"""``rostools bridge`` with JavaScript clients nobody here wrote: the npm ``FoxgloveClient``
of ``@foxglove/ws-protocol`` 0.8.0 in node, and Foxglove Studio 1.48 in Debian's chromium."""

from __future__ import annotations

import base64
import re
import struct
from pathlib import Path

import pytest

from tests.conftest import MasterInfo
from tests.support.env import needs_ros1
from tests.support.foxglove import ros_string, start_bridge
from tests.support.procs import start_cli, start_ros1_node
from tests.support.web import NodeClient, browser_missing, node_missing, run_studio, studio_shell

pytestmark = [pytest.mark.interop, needs_ros1]

ARTIFACTS = Path(__file__).resolve().parent.parent.parent / "build" / "test-artifacts"


@pytest.mark.parametrize("subprotocol", ["foxglove.websocket.v1", "foxglove.sdk.v1"])
def test_the_npm_foxglove_client_reads_calls_and_publishes(
    any_master: MasterInfo, subprotocol: str
) -> None:
    if reason := node_missing():
        pytest.skip(reason)
    env = any_master.ros_env
    talker = start_ros1_node("talker.py", ["/chatter", "20"], env)
    server = start_ros1_node("add_two_ints_server.py", [], env)
    listener = start_ros1_node("listener.py", ["/from_node_js"], env)
    bridge, url = start_bridge(any_master.cli_env)
    client = NodeClient(url, subprotocol)
    try:
        assert client.expect(lambda e: e["event"] == "open")["protocol"] == subprotocol
        info = client.expect(lambda e: e["event"] == "serverInfo")
        assert "services" in info["capabilities"]
        client.expect(
            lambda e: (
                e["event"] == "advertise" and any(c["topic"] == "/chatter" for c in e["channels"])
            ),
            30,
        )
        client.send(do="subscribe", topic="/chatter")
        message = client.expect(lambda e: e["event"] == "message", 30)
        assert message["topic"] == "/chatter"
        assert base64.b64decode(message["data"])[4:].startswith(b"hello ")
        client.send(do="unsubscribe", topic="/chatter")

        client.expect(
            lambda e: (
                e["event"] == "advertiseServices"
                and any(s["name"] == "/add_two_ints" for s in e["services"])
            ),
            30,
        )
        request = base64.b64encode(struct.pack("<qq", 20, 22)).decode()
        client.send(do="callService", service="/add_two_ints", data=request, callId=5)
        response = client.expect(lambda e: e["event"] == "serviceCallResponse", 30)
        assert (response["callId"], response["encoding"]) == (5, "ros1")
        assert base64.b64decode(response["data"]) == struct.pack("<q", 42)

        client.send(do="getParameters", names=["/rosdistro"], id="d")
        values = client.expect(lambda e: e["event"] == "parameterValues" and e.get("id") == "d")
        assert values["parameters"][0]["name"] == "/rosdistro"

        listener.expect("ready", 30)
        client.send(do="advertise", topic="/from_node_js", encoding="ros1",
                    schemaName="std_msgs/String", schema="string data\n")  # fmt: skip
        data = base64.b64encode(ros_string("from node")).decode()
        for _ in range(60):  # until the listener has connected and prints it
            client.send(do="publish", topic="/from_node_js", data=data)
            try:
                listener.expect("got from node", 0.5)
                break
            except AssertionError:
                continue
        else:
            raise AssertionError("the rospy listener never got the node client's message")
    finally:
        client.stop()
        bridge.stop()
        for proc in (talker, server, listener):
            proc.stop()


def red_image(width: int = 64, height: int = 48) -> str:
    """``topic pub``'s YAML for an rgb8 image, all red."""
    data = ",".join(["255,0,0"] * (width * height))
    return (
        f"{{header: auto, height: {height}, width: {width}, encoding: rgb8, "
        f"step: {width * 3}, data: [{data}]}}"
    )


def test_foxglove_studio_shows_topics_messages_and_an_image(any_master: MasterInfo) -> None:
    if reason := browser_missing():
        pytest.skip(reason)
    from matplotlib.image import imread

    talker = start_ros1_node("talker.py", ["/chatter", "10"], any_master.ros_env)
    camera = start_cli(
        "topic", "pub", "-r", "5", "/camera", "sensor_msgs/Image", red_image(),
        env=any_master.cli_env,
    )  # fmt: skip
    bridge, url = start_bridge(any_master.cli_env)
    ARTIFACTS.mkdir(parents=True, exist_ok=True)
    shot = ARTIFACTS / f"bridge-studio-{any_master.kind}.png"
    try:
        with studio_shell() as page:
            seen = run_studio(
                f"{page}?ds=foxglove-websocket&ds.url={url}", shot,
                "--topic", "/chatter", "--topic", "/camera",
                "--text", r"hello \d+", "--image", "/camera", timeout=120,
            )  # fmt: skip
    finally:
        bridge.stop()
        camera.stop()
        talker.stop()
    assert "error" not in seen, seen
    topics = seen["topics"]
    assert "/chatter\nstd_msgs/String" in topics and "/camera\nsensor_msgs/Image" in topics
    assert re.search(r"/chatter\nstd_msgs/String\n\d+\n[\d.]+ Hz", topics)  # with its rate
    assert seen["raw"].startswith("hello ")  # the Raw Messages panel shows the payload
    pixels = imread(shot)  # floats in [0, 1], RGBA
    red = (pixels[..., 0] > 0.9) & (pixels[..., 1] < 0.1) & (pixels[..., 2] < 0.1)
    assert red.sum() > 10_000, f"the Image panel drew {red.sum()} red pixels: see {shot}"
