"""``rostools demo``: the main job in ten seconds, with nothing installed and nothing left running.

An in-process master, a talker on /chatter, an AddTwoInts service and a few parameters; then
the real commands against them, each shown as it would be typed: topic list, echo, hz, a
service call, three seconds recorded to ``demo.mcap`` and its ``bag info``. The recording
starts first and runs beside the steps before it; its output is shown at its turn.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import signal
import subprocess
import sys
import threading
from pathlib import Path
from typing import TYPE_CHECKING, Annotated

import typer

from rostools.cli.output import check_writable, flush, put as say
from rostools.errors import RostoolsError, UsageError
from rostools.node.notice import Notice, to_stderr

if TYPE_CHECKING:
    from rostools.node.node import LiveNode

app = typer.Typer(name="demo", add_completion=False)

#: Where the demo records unless told (``-O``); a file of that name is kept (``_free_name``).
DEFAULT_OUTPUT = Path("demo.mcap")

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
#: The step that starts before the others and runs beside them (the recording's three
#: seconds are most of the demo's time otherwise).
AHEAD = "three seconds recorded"
#: Notices the demo's own nodes keep to themselves: their master runs in this process, so
#: it is never lost; a loaded machine only makes its answer slow.
OWN_MASTER = ("master_lost", "master_back")


class DemoGraph:
    """The demo's talker and service, on their own event loop in a thread."""

    def __init__(self, master_uri: str) -> None:
        self.master_uri = master_uri
        self.loop = asyncio.new_event_loop()
        self.stop = asyncio.Event()
        self.ready = threading.Event()
        self.error: BaseException | None = None
        #: The talker's node and the service's, once they run.
        self.nodes: list[LiveNode] = []
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
        from rostools.msgs.topictype import ServiceType, TopicType
        from rostools.node.node import LiveNode

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
        talker.notify = server.notify = _not_about_own_master
        self.nodes = [talker, server]
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


def _not_about_own_master(notice: Notice) -> None:
    if notice.event not in OWN_MASTER:
        to_stderr(notice)


def _shown(argv: list[str]) -> str:
    return " ".join(f"'{a}'" if " " in a else a for a in argv)


def _start(argv: list[str], env: dict[str, str], capture: bool) -> subprocess.Popen[bytes]:
    return subprocess.Popen(
        [sys.executable, "-m", "rostools", *argv], env=env, stderr=subprocess.STDOUT,
        stdout=subprocess.PIPE if capture else None, stdin=subprocess.DEVNULL,
    )  # fmt: skip


def _run_step(
    title: str, argv: list[str], env: dict[str, str], ahead: subprocess.Popen[bytes] | None
) -> None:
    """Show the step and run it; or, started ahead, wait for it and show what it printed."""
    say(f"\n# {title}\n$ rostools {_shown(argv)}\n")
    flush()
    proc = ahead if ahead is not None else _start(argv, env, capture=False)
    out, _ = proc.communicate()
    if out:
        say(out.decode(errors="replace"))
    if proc.returncode != 0:
        raise RostoolsError(
            f"the demo step 'rostools {_shown(argv)}' failed (exit {proc.returncode})"
        )


def _free_name() -> Path:
    """``demo.mcap``, or ``demo-2.mcap``, ``-3`` ... where a run before left its recording."""
    path, n = DEFAULT_OUTPUT, 1
    while path.exists() or path.with_name(path.name + ".active").exists():
        n += 1
        path = DEFAULT_OUTPUT.with_name(f"{DEFAULT_OUTPUT.stem}-{n}{DEFAULT_OUTPUT.suffix}")
    return path


@app.command()
def demo(
    output: Annotated[
        Path | None,
        typer.Option(
            "--output",
            "-O",
            help="Where to record [default: demo.mcap here (demo-2.mcap ... if it is taken),"
            " else in a temporary folder].",
            show_default=False,
        ),
    ] = None,
) -> None:
    """Try rostools in ten seconds: a master, a talker, a service, a recording."""
    from rostools.master.server import MasterThread

    if output is not None:
        check_writable(output)
    else:
        output = _free_name()
        try:
            check_writable(output)
        except UsageError:  # a read-only folder: the demo still runs
            import tempfile

            output = Path(tempfile.mkdtemp(prefix="rostools-demo-")) / DEFAULT_OUTPUT.name
            say(f"(this folder is read-only: recording to {output})\n")
        else:
            if output != DEFAULT_OUTPUT:  # a run before left its recording: it stays
                say(f"({DEFAULT_OUTPUT} is here already: recording to {output})\n")

    with MasterThread() as master:
        env = {k: v for k, v in os.environ.items() if k != "ROS_HOSTNAME"}
        env.update(ROS_MASTER_URI=master.uri, ROS_IP="127.0.0.1")
        say(
            f"rostools demo: a master at {master.uri} (in this process), a talker on /chatter,\n"
            "an /add_two_ints service and /demo parameters. Each step runs the real command.\n"
        )
        steps = [(title, [a.replace("{out}", str(output)) for a in argv]) for title, argv in STEPS]
        with DemoGraph(master.uri):
            ahead = _start(dict(steps)[AHEAD], env, capture=True)
            try:
                for title, argv in steps:
                    _run_step(title, argv, env, ahead if title == AHEAD else None)
            finally:
                if ahead.poll() is None:  # a step before it failed: the recording ends now
                    ahead.send_signal(signal.SIGINT)
                    ahead.communicate()
    say(
        f"\nDone; nothing is left running, and {output} is yours. Next: 'rostools core' in one\n"
        "terminal, then any of these commands in another ('rostools -h' lists them all).\n"
    )
