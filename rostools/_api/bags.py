"""Bags for the API: ``record(topics, path)`` around a block, ``read_bag`` as typed messages.

A recording is ``bag record``'s ``Recorder`` on a node of its own; its file is written as
``NAME.active`` and renamed when the recording stops, as ``bag record`` does.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Collection, Iterator, Sequence
from pathlib import Path
from typing import NamedTuple

from rostools._api import messages
from rostools._api.nodetask import NodeTask
from rostools.bag.formats.access import format_for_name, open_bag, require_ros1
from rostools.bag.formats.model import lost_data
from rostools.bag.live.follow import Follower
from rostools.bag.live.recorder import Recorder, RecordOptions
from rostools.errors import RostoolsError, TimeoutExpired, UsageError
from rostools.msgs.message import Message, Time
from rostools.node.node import LiveNode

#: How long a recording may take to subscribe and open its file before it gives up.
START_TIMEOUT = 10.0


class BagMessage(NamedTuple):
    """One message read from a bag: topic, typed message, and the time it was recorded."""

    topic: str
    message: Message
    time: Time


def read_bag(path: str | Path, topics: Collection[str] | None = None) -> Iterator[BagMessage]:
    """The messages of a ``.bag`` or MCAP file in time order, optionally of some topics.

    A damaged file gives every message that reads, then raises ``DataLossError`` (the CLI's
    exit 6) naming what it left out.
    """
    with open_bag(path) as reader:
        require_ros1(reader, "read_bag", topics)
        count = 0
        for conn, t_ns, data in reader.messages(topics=topics):
            decode = messages.decoder(conn.type, conn.md5sum, conn.definition)
            count += 1
            yield BagMessage(conn.topic, decode(data), Time.from_nsec(t_ns))
        if reader.damage:
            raise lost_data(f"read {count} messages of {path}", reader.damage)


def convert_to_ros2(
    sources: str | Path | Sequence[str | Path],
    dst: str | Path,
    *,
    distro: str | None = None,
    types: str | Path | None = None,
    exclude: Collection[str] = (),
    compression: str = "zstd",
    overwrite: bool = False,
) -> Path:
    """ROS 1 bags into a rosbag2 folder (``dst.mcap``: the MCAP alone); returns ``dst``.

    As ``rostools bag convert SRC... DST --to ros2``: ``distro`` (default the newest LTS
    rosbags knows), ``types`` (a YAML file of renames and definitions), ``exclude`` (topics
    left out). A type with no ROS 2 form is a ``RostoolsError`` naming it, before anything is
    written; a damaged input is converted as far as it reads, then ``DataLossError`` names
    what was left out.
    """
    from rostools.bag.formats.ros2types import DEFAULT_DISTRO
    from rostools.bag.tools.ros2convert import convert_to_ros2 as run

    report = run(
        sources, dst, distro=distro or DEFAULT_DISTRO, types=types, exclude=exclude,
        compression=compression, overwrite=overwrite,
    )  # fmt: skip
    report.raise_if_lost()
    return report.output


class LiveRecorder(NodeTask):
    """A recorder of the live graph on a node of its own, on the API's loop or the caller's.

    A subclass makes the recorder (``_make``) and says when it is under way (``_ready``).
    """

    node_name = "rostools_record"

    def _make(self, node: LiveNode) -> Follower:
        raise NotImplementedError

    def _ready(self, node: LiveNode) -> bool:
        raise NotImplementedError

    async def _start(self, what: str) -> None:
        node = await self._open_node()
        try:
            follower = self._make(node)
        except BaseException:
            await node.close()
            raise
        self._launch(node, follower.run)  # the file is completed at exit too
        assert self._task is not None
        deadline = time.monotonic() + START_TIMEOUT
        while not self._ready(node):
            if self._task.done():
                await self._finish()
                raise RostoolsError(f"{what} stopped at once")
            if time.monotonic() > deadline:
                await self._finish()
                raise TimeoutExpired(f"{what} did not start")
            await asyncio.sleep(0.005)


class Recording(LiveRecorder):
    """Records topics into a bag while it runs: ``with record(["/a"], "a.bag") as rec:``.

    The bag is complete when the recording stops (the end of the ``with``, or ``stop()``).
    """

    def __init__(
        self,
        topics: Sequence[str],
        path: str | Path,
        master_uri: str | None = None,
        *,
        compression: str | None = None,
    ) -> None:
        if isinstance(topics, str):
            topics = [topics]
        if not topics:
            raise UsageError("record needs at least one topic")
        super().__init__(master_uri)
        self.topics = list(topics)
        self.path = Path(path)
        self.compression = compression
        self._recorder: Recorder | None = None

    def _make(self, node: LiveNode) -> Follower:
        opts = RecordOptions(
            topics=list(self.topics),
            base=self.path,
            format=format_for_name(self.path),
            compression=self.compression,
            min_space=0,  # a test's bag is small; the disk check is for long recordings
        )
        self._recorder = Recorder(node, opts)
        return self._recorder

    def _ready(self, node: LiveNode) -> bool:
        rec = self._recorder
        return (
            rec is not None
            and rec.current_file is not None
            and (set(rec.opts.topics) <= set(node.subscribers))
        )

    async def start_async(self) -> Recording:
        """Subscribe and open the file, on the running loop."""
        await self._start(f"the recording into {self.path}")
        return self

    async def stop_async(self) -> Path:
        """Stop, close the file; its path."""
        await self._finish()
        return self.path

    def start(self) -> Recording:
        """Start recording (on the API's background loop)."""
        return self._start_on_api_loop()

    def stop(self) -> Path:
        """Stop recording and close the bag; its path."""
        self._stop_on_api_loop()
        return self.path

    @property
    def counts(self) -> dict[str, int]:
        """Messages received so far, per topic."""
        rec = self._recorder
        return {} if rec is None else {t: s.messages for t, s in rec.stats.items()}

    def messages(self, topics: Collection[str] | None = None) -> list[BagMessage]:
        """Every message of the bag, once it is stopped."""
        if self.running:
            raise UsageError("stop() the recording before reading it")
        return list(read_bag(self.path, topics))


def record(
    topics: Sequence[str],
    path: str | Path,
    master_uri: str | None = None,
    *,
    compression: str | None = None,
) -> Recording:
    """A recording of ``topics`` into ``path`` (``.mcap``: MCAP, else ``.bag``).

    Use it as a context manager (``with`` or ``async with``), or ``start()``/``stop()``.
    """
    return Recording(topics, path, master_uri, compression=compression)
