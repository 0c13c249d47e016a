"""``rostools demo``: the main job in ten seconds, with nothing installed and nothing left running.

An in-process master, a talker on /chatter, an AddTwoInts service and a few parameters; then
the real commands against them, each shown as it would be typed: topic list, echo, hz, a
service call, three seconds recorded to ``demo.mcap`` and its ``bag info``.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import subprocess
import sys
import threading
from pathlib import Path
from typing import Annotated

import typer

from rostools.cli.output import check_writable, flush, put as say
from rostools.errors import RostoolsError, UsageError

app = typer.Typer(name="demo", add_completion=False)

#: (what it shows, the command line after ``rostools``).
STEPS: list[tuple[str, list[str]]] = [
    ("the topics on the graph", ["topic", "list"]),
    ("three messages", ["topic", "echo", "/chatter", "-n", "3"]),
    ("the rate", ["topic", "hz", "/chatter", "--timeout", "1.3"]),
    ("a service call", ["service", "call", "/add_two_ints", "{a: 2, b: 3}"]),
    ("the parameters", ["param", "get", "/demo"]),
    ("three seconds recorded", ["bag", "record", "/chatter", "-O", "{out}", "--duration", "3"]),
    ("what was recorded", ["bag", "info", "{out}"]),
]


class DemoGraph:
    """The demo's talker and service, on their own event loop in a thread."""

    def __init__(self, master_uri: str) -> None:
        self.master_uri = master_uri
        self.loop = asyncio.new_event_loop()
        self.stop = asyncio.Event()
        self.ready = threading.Event()
        self.error: BaseException | None = None
        self.thread = threading.Thread(target=self._run, name="rostools-demo", daemon=True)

    def __enter__(self) -> DemoGraph:
        self.thread.start()
        self.ready.wait(10)
        if self.error is not None:
            raise self.error
        return self

    def __exit__(self, *exc: object) -> None:
        self.loop.call_soon_threadsafe(self.stop.set)
        self.thread.join(5)

    def _run(self) -> None:
        try:
            self.loop.run_until_complete(self._main())
        except BaseException as err:  # noqa: BLE001 - handed to the starting thread
            self.error = err
            self.ready.set()
        finally:
            self.loop.close()

    async def _main(self) -> None:
        from rostools.msgs.codec import Codec
        from rostools.msgs.store import BuiltinSource, TypeStore
        from rostools.msgs.topictype import TopicType
        from rostools.node.node import LiveNode
        from rostools.node.service import ServiceType

        store = TypeStore([BuiltinSource()])
        srv_type = ServiceType.of(store, "rospy_tutorials/AddTwoInts")  # defines its messages
        codec = Codec.of(store)
        string = codec.message_class("std_msgs/String")
        answer = codec.message_class("rospy_tutorials/AddTwoIntsResponse")

        def add(request: bytes) -> bytes:
            req = codec.decode("rospy_tutorials/AddTwoIntsRequest", request)
            return answer(req.a + req.b).serialize()

        # the demo's master is loopback-only, so its nodes are too, whatever the host's name
        talker = await LiveNode("talker", self.master_uri, host="127.0.0.1").start()
        server = await LiveNode("add_two_ints_server", self.master_uri, host="127.0.0.1").start()
        try:
            pub = await talker.advertise("/chatter", TopicType.of(store, "std_msgs/String"))
            await server.advertise_service("/add_two_ints", srv_type, add)
            params = {"robot_name": "demo_bot", "max_speed": 0.5, "sensors": ["lidar", "imu"]}
            await server.master.set_param("/demo", params)
            self.ready.set()
            n = 0
            while not self.stop.is_set():
                pub.publish(string(f"hello world {n}").serialize())
                n += 1
                with contextlib.suppress(asyncio.TimeoutError):
                    await asyncio.wait_for(self.stop.wait(), 0.1)  # 10 Hz
        finally:
            await talker.close()
            await server.close()


def _run_step(title: str, argv: list[str], env: dict[str, str]) -> None:
    shown = " ".join(f"'{a}'" if " " in a else a for a in argv)
    say(f"\n# {title}\n$ rostools {shown}\n")
    flush()
    done = subprocess.run(
        [sys.executable, "-m", "rostools", *argv], env=env, stderr=subprocess.STDOUT, check=False
    )
    if done.returncode != 0:
        raise RostoolsError(f"the demo step 'rostools {shown}' failed (exit {done.returncode})")


@app.command()
def demo(
    output: Annotated[
        Path | None,
        typer.Option(
            "--output",
            "-O",
            help="Where to record [default: demo.mcap here, else in a temporary folder].",
            show_default=False,
        ),
    ] = None,
) -> None:
    """Try rostools in ten seconds: a master, a talker, a service, a recording."""
    from rostools.master.server import MasterThread

    if output is not None:
        check_writable(output)
    else:
        output = Path("demo.mcap")
        try:
            check_writable(output)
        except UsageError:  # a read-only folder: the demo still runs
            import tempfile

            output = Path(tempfile.mkdtemp(prefix="rostools-demo-")) / "demo.mcap"
            say(f"(this folder is read-only: recording to {output})\n")

    with MasterThread() as master:
        env = {k: v for k, v in os.environ.items() if k != "ROS_HOSTNAME"}
        env.update(ROS_MASTER_URI=master.uri, ROS_IP="127.0.0.1")
        say(
            f"rostools demo: a master at {master.uri} (in this process), a talker on /chatter,\n"
            "an /add_two_ints service and /demo parameters. Each step runs the real command.\n"
        )
        with DemoGraph(master.uri):
            for title, argv in STEPS:
                _run_step(title, [a.replace("{out}", str(output)) for a in argv], env)
    say(
        f"\nDone; nothing is left running, and {output} is yours. Next: 'rostools core' in one\n"
        "terminal, then any of these commands in another ('rostools -h' lists them all).\n"
    )
