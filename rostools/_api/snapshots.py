"""Snapshots for the API: ``snapshot()`` keeps the graph's last seconds, ``write()`` saves them.

It is ``bag snapshot``'s ``Snapshotter`` on a node of its own, with its services (so ``bag
trigger`` and rosbag_snapshot's clients can trigger it too), run as ``record`` runs.
"""

from __future__ import annotations

import asyncio
from collections.abc import Sequence
from pathlib import Path

from rostools._api import loop
from rostools._api.bags import LiveRecorder
from rostools.bag.live.bagfile import write_failure
from rostools.bag.live.follow import Follower
from rostools.bag.live.snapshot import SnapshotOptions, Snapshotter
from rostools.bag.live.snapshot_srv import SnapshotRequest, window
from rostools.errors import UsageError, cannot_write
from rostools.node.node import LiveNode


class SnapshotRecorder(LiveRecorder):
    """Keeps the last ``duration`` seconds of topics in memory: ``with snapshot() as snap:``.

    ``write()`` saves a window of them (and, with ``after``, the live messages that follow)
    into a bag in ``folder`` and returns its path once the file is complete.
    """

    node_name = "rostools_snapshot"

    def __init__(
        self,
        topics: Sequence[str] | None = None,
        folder: str | Path = ".",
        master_uri: str | None = None,
        *,
        duration: float = 30.0,
        size_mb: int = 256,
        exclude: Sequence[str] = (),
        storage: str = "bag",
        poll_period: float | None = None,
    ) -> None:
        super().__init__(master_uri)
        self.topics = [topics] if isinstance(topics, str) else list(topics or [])
        self.folder = Path(folder)
        if storage not in ("bag", "mcap"):
            raise UsageError(f"unknown storage {storage!r} (bag or mcap)")
        self.options = SnapshotOptions(
            topics=list(self.topics), all=not self.topics, exclude=list(exclude),
            base=self.folder / f"snapshot.{storage}", format=storage, duration=duration,
            size=size_mb * 1024 * 1024, min_space=0,
        )  # fmt: skip
        self.options.check()
        self.poll_period = poll_period
        self._snap: Snapshotter | None = None

    def _make(self, node: LiveNode) -> Follower:
        self._snap = Snapshotter(node, self.options)
        if self.poll_period is not None:
            self._snap.poll_period = self.poll_period
        return self._snap

    def _ready(self, node: LiveNode) -> bool:
        snap = self._snap
        return (
            snap is not None
            and snap.announce is not None
            and (set(snap.opts.topics) <= set(node.subscribers))
        )

    async def start_async(self) -> SnapshotRecorder:
        """Subscribe and start buffering, on the running loop (``folder`` is made if need be)."""
        self._make_folder()
        await self._start("the snapshot recorder")
        return self

    def _make_folder(self) -> None:
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
        except OSError as err:
            raise cannot_write(self.folder, err.strerror or str(err)) from err

    async def stop_async(self) -> None:
        """Stop buffering (files being written are completed first)."""
        await self._finish()

    def start(self) -> SnapshotRecorder:
        """Start buffering (on the API's background loop)."""
        return self._start_on_api_loop()

    def stop(self) -> None:
        """Stop buffering; files being written are completed first."""
        self._stop_on_api_loop()

    async def write_async(
        self,
        name: str | None = None,
        *,
        before: float | None = None,
        after: float = 0.0,
        topics: Sequence[str] = (),
    ) -> Path:
        """Write the last ``before`` seconds (None: all buffered), and ``after`` more, to a bag.

        ``name`` ending in ``.bag`` or ``.mcap`` is the file's name in ``folder``; otherwise
        it is a prefix for a dated name. Returns once the file is complete.
        """
        snap = self._snap
        if snap is None or not self.running:
            raise UsageError("start() the snapshot recorder before writing")
        self._make_folder()  # again: it may have been cleaned away while buffering
        start, stop = window(snap.clock.now(), before, after)
        job = snap.trigger(SnapshotRequest(name or "", list(topics), start, stop), remote=False)
        while job.is_alive() or job in snap.jobs:
            await asyncio.sleep(0.01)
        if job.error is not None:
            raise write_failure(job.error, "the snapshot stopped")
        return job.path

    def write(
        self,
        name: str | None = None,
        *,
        before: float | None = None,
        after: float = 0.0,
        topics: Sequence[str] = (),
    ) -> Path:
        """Write a snapshot and wait until its file is complete (see ``write_async``)."""
        return loop.run(self.write_async(name, before=before, after=after, topics=topics))

    def pause(self) -> None:
        """Stop buffering new messages; what is buffered stays until resumed."""
        if self._snap is not None:
            self._snap.set_paused(True)

    def resume(self) -> None:
        """Buffer new messages again."""
        if self._snap is not None:
            self._snap.set_paused(False)


def snapshot(
    topics: Sequence[str] | None = None,
    folder: str | Path = ".",
    master_uri: str | None = None,
    *,
    duration: float = 30.0,
    size_mb: int = 256,
) -> SnapshotRecorder:
    """A snapshot recorder of ``topics`` (None: every topic) into ``folder``, made if need be.

    Use it as a context manager (``with`` or ``async with``), or ``start()``/``stop()``;
    ``write(before=10)`` saves the last ten seconds.
    """
    return SnapshotRecorder(topics, folder, master_uri, duration=duration, size_mb=size_mb)
