"""``roscore`` done by rostools: the master, the parameters roscore sets, and clean stops."""

from __future__ import annotations

import asyncio
import ipaddress
import os
import signal
import uuid
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from urllib.parse import urlsplit

from rostools.errors import RostoolsError
from rostools.graph.connection import Frame
from rostools.graph.node import Node
from rostools.master.server import Master
from rostools.msgs.store import BuiltinSource, TypeStore

DEFAULT_PORT = 11311
#: What roscore publishes about itself; values end in a newline as ``rosversion`` prints them.
ROSDISTRO = "noetic\n"
ROSVERSION = "1.16.0\n"


@dataclass(frozen=True)
class Address:
    """Where the master listens and the host name it gives out."""

    bind: str
    port: int
    advertise: str

    @property
    def uri(self) -> str:
        """The master URI nodes use."""
        return f"http://{self.advertise}:{self.port}/"


def choose_address(
    host: str | None, port: int | None, env: Mapping[str, str] | None = None
) -> Address:
    """Apply ``--host``/``--port``, ``ROS_IP``, ``ROS_HOSTNAME`` and ``ROS_MASTER_URI``.

    Loopback unless told otherwise. A host name (not an address) listens on every interface,
    as a master that others must reach by name has to.
    """
    if env is None:
        env = os.environ
    if port is None:
        uri_port = (
            urlsplit(env.get("ROS_MASTER_URI", "")).port if env.get("ROS_MASTER_URI") else None
        )
        port = uri_port or DEFAULT_PORT
    name = host or env.get("ROS_IP") or env.get("ROS_HOSTNAME") or "127.0.0.1"
    if name == "localhost":
        bind = "127.0.0.1"
    else:
        try:
            ipaddress.ip_address(name)
            bind = name
        except ValueError:
            bind = "0.0.0.0"  # noqa: S104 - a named host must be reachable by that name
    advertise = env.get("ROS_HOSTNAME") or ("localhost" if name == "127.0.0.1" else name)
    return Address(bind, port, advertise)


async def run_core(address: Address, ready: Callable[[Master, str], None]) -> None:
    """Serve until SIGINT, SIGTERM or a ``shutdown`` call."""
    master = Master(address.bind, address.port, address.advertise)
    try:
        await master.start()
    except OSError as err:
        raise RostoolsError(
            f"cannot listen on {address.bind}:{address.port}: {err.strerror or err}",
            hint="another program holds the port; pick one with --port",
        ) from None
    assert master.api is not None
    run_id = str(uuid.uuid1())
    for key, value in (("/run_id", run_id), ("/rosdistro", ROSDISTRO), ("/rosversion", ROSVERSION)):
        master.api.params.set(key, value)
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGINT, signal.SIGTERM):
        loop.add_signal_handler(sig, master.stopped.set)
    rosout = _Rosout(master, address.advertise)
    await rosout.start()
    try:
        ready(master, run_id)
        await master.wait()
    finally:
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.remove_signal_handler(sig)
        await rosout.stop()
        await master.stop()


class _Rosout:
    """roscore's /rosout, kept as roscore's launch file keeps it.

    Killed (``node kill``), it is started again, as roslaunch respawns it. Replaced by another
    node named /rosout (a real rosout, say), it leaves for good, as roscpp's rosout would,
    rather than keep serving connections the master has forgotten.
    """

    def __init__(self, master: Master, host: str) -> None:
        self.master = master
        self.uri = f"http://127.0.0.1:{master.port}/"
        self.host = host
        self.node: Node | None = None
        self._watch: asyncio.Task[None] | None = None

    async def start(self) -> None:
        """Start the node and watch for ``shutdown`` calls to it."""
        self.node = await start_rosout(self.uri, self.host)
        self._watch = asyncio.create_task(self._respawn())

    async def _respawn(self) -> None:
        while self.node is not None:
            await self.node.shutdown_requested.wait()
            await self.node.close()
            self.node = None
            assert self.master.api is not None
            if "/rosout" not in self.master.api.registry.nodes:  # killed, not replaced
                self.node = await start_rosout(self.uri, self.host)

    async def stop(self) -> None:
        """Stop watching and close the node."""
        if self._watch is not None:
            self._watch.cancel()
        if self.node is not None and not self.node.shutdown_requested.is_set():
            await self.node.close()


async def start_rosout(master_uri: str, host: str) -> Node:
    """roscore's /rosout node: every node's /rosout messages, republished on /rosout_agg."""
    from rostools.graph.topic import TopicType

    store = TypeStore([BuiltinSource()])
    log_type = TopicType.of(store, "rosgraph_msgs/Log")
    node = await Node(
        "/rosout", master_uri, host="127.0.0.1" if host == "localhost" else host
    ).start()
    agg = await node.advertise("/rosout_agg", log_type, queue_size=1000)

    def forward(frames: list[Frame], conn: object, now: float) -> None:
        for frame in frames:
            agg.publish(frame)

    await node.subscribe("/rosout", forward, log_type)
    await add_logger_services(node, store)
    return node


async def add_logger_services(node: Node, store: TypeStore) -> None:
    """``~get_loggers`` and ``~set_logger_level``, which every rospy and roscpp node offers."""
    from rostools.graph.service import ServiceType
    from rostools.msgs.codec import Codec

    codec = Codec.of(store)
    levels = {"ros": "info"}
    get_type, set_type = (
        ServiceType.of(store, "roscpp/GetLoggers"),
        ServiceType.of(store, "roscpp/SetLoggerLevel"),
    )

    def get_loggers(request: bytes) -> bytes:
        logger = codec.message_class("roscpp/Logger")
        loggers = [logger(name, level) for name, level in sorted(levels.items())]
        return codec.message_class("roscpp/GetLoggersResponse")(loggers).serialize()

    def set_level(request: bytes) -> bytes:
        msg = codec.decode("roscpp/SetLoggerLevelRequest", request)
        levels[msg.logger] = msg.level.lower()
        return b""

    await node.advertise_service("~get_loggers", get_type, get_loggers)
    await node.advertise_service("~set_logger_level", set_type, set_level)
