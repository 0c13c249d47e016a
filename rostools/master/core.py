"""``roscore`` done by rostools: the master, the parameters roscore sets, and clean stops."""

from __future__ import annotations

import asyncio
import os
import uuid
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from urllib.parse import urlsplit

from rostools.errors import RostoolsError
from rostools.master.server import MasterServer
from rostools.msgs.store import BuiltinSource, TypeStore
from rostools.node.connection import Frame
from rostools.node.listen import raise_descriptor_limit
from rostools.node.node import LiveNode
from rostools.node.session import STOP_SIGNALS
from rostools.rosgraph.network import (
    ANY_ADDRESS,
    address_override,
    bind_address,
    host_name,
    is_loopback,
)

DEFAULT_PORT = 11311
#: ``--host`` values that mean every interface.
_EVERYWHERE = ("0.0.0.0", "::")  # noqa: S104
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
    """Apply ``--host``/``--port``, ``ROS_HOSTNAME``, ``ROS_IP`` and ``ROS_MASTER_URI``.

    With none of them, loopback only: nothing is reachable from other hosts unless asked.
    Otherwise rosmaster's rules: the name is given out as it is, and the master listens on
    every interface unless the name is a loopback one. ``0.0.0.0`` listens everywhere and
    gives out this host's name.
    """
    if env is None:
        env = os.environ
    if port is None:
        uri_port = (
            urlsplit(env.get("ROS_MASTER_URI", "")).port if env.get("ROS_MASTER_URI") else None
        )
        port = uri_port or DEFAULT_PORT
    name = host or address_override(env)
    if not name:
        return Address("127.0.0.1", port, "localhost")
    if name in _EVERYWHERE:
        named = address_override(env)
        advertise = named if named and named not in _EVERYWHERE else host_name({})
        return Address(ANY_ADDRESS, port, advertise)
    return Address(bind_address(name), port, name)


async def start_master(bind: str, port: int, advertise: str, hint: str) -> MasterServer:
    """A master serving on ``bind:port``, with roscore's /run_id, /rosdistro and /rosversion.

    A port it cannot listen on is one line, with ``hint``.
    """
    master = MasterServer(bind, port, advertise)
    try:
        await master.start()
    except OSError as err:
        raise RostoolsError(
            f"cannot listen on {bind}:{port}: {err.strerror or err}", hint=hint
        ) from err
    assert master.api is not None
    run_id = str(uuid.uuid1())
    for key, value in (("/run_id", run_id), ("/rosdistro", ROSDISTRO), ("/rosversion", ROSVERSION)):
        master.api.params.set(key, value)
    return master


async def run_core(address: Address, ready: Callable[[MasterServer, str], None]) -> None:
    """Serve until SIGINT, SIGTERM, SIGHUP or a ``shutdown`` call."""
    raise_descriptor_limit()  # a socket per client, as every server needs
    master = await start_master(
        address.bind, address.port, address.advertise,
        "another program holds the port; pick one with --port",
    )  # fmt: skip
    loop = asyncio.get_running_loop()
    for sig in STOP_SIGNALS:
        loop.add_signal_handler(sig, master.stopped.set)
    rosout = _Rosout(master, address.advertise)
    await rosout.start()
    try:
        assert master.api is not None
        ready(master, str(master.api.params.get("/run_id")))
        await master.wait()
    finally:
        await rosout.stop()
        await master.stop()
        for sig in STOP_SIGNALS:  # caught until now: a second Ctrl-C must not cut the stop short
            loop.remove_signal_handler(sig)


class _Rosout:
    """roscore's /rosout, kept as roscore's launch file keeps it.

    Killed (``node kill``), it is started again, as roslaunch respawns it. Replaced by another
    node named /rosout (a real rosout, say), it leaves for good, as roscpp's rosout would,
    rather than keep serving connections the master has forgotten.
    """

    def __init__(self, master: MasterServer, host: str) -> None:
        self.master = master
        # it calls the master on loopback, which a master listening anywhere also answers
        local = master.host if is_loopback(master.host) else "127.0.0.1"
        self.uri = f"http://{local}:{master.port}/"
        self.host = host
        self.node: LiveNode | None = None
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


async def start_rosout(master_uri: str, host: str) -> LiveNode:
    """roscore's /rosout node: every node's /rosout messages, republished on /rosout_agg."""
    from rostools.msgs.topictype import TopicType

    store = TypeStore([BuiltinSource()])
    log_type = TopicType.of(store, "rosgraph_msgs/Log")
    node = await LiveNode(
        "/rosout", master_uri, host="127.0.0.1" if host == "localhost" else host
    ).start()
    agg = await node.advertise("/rosout_agg", log_type, queue_size=1000)

    def forward(frames: list[Frame], conn: object, now: float) -> None:
        for frame in frames:
            agg.publish(frame)

    await node.subscribe("/rosout", forward, log_type)
    return node
