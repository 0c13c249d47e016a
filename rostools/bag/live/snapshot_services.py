"""What a ``Snapshotter`` serves on the graph, and the ``~written`` topic its clients wait on.

- ``trigger_snapshot`` (rosbag_snapshot_msgs/TriggerSnapshot), in the node's namespace as
  rosbag_snapshot's: the answer names the file once it is under way (rosbag_snapshot
  answers once it is written, with no name);
- ``enable_snapshot`` (std_srvs/SetBool), rosbag_snapshot's pause (false) and resume (true);
- ``~trigger`` (std_srvs/Trigger): the local window (``--before``/``--after``);
- ``~pause``, ``~resume`` (std_srvs/Trigger);
- ``~stop`` (std_srvs/Trigger): ends every file written until stopped (``--continue``);
- ``~written`` (std_msgs/String): one JSON object per file once complete or failed:
  ``name``, ``messages``, ``bytes``, ``start``, ``end``, ``duration``, ``window_ns``,
  ``seconds``, ``lost`` (``lost_exact``, ``evicted``, ``drops``), ``error``.
"""

from __future__ import annotations

import json
import re
import struct
from collections.abc import Callable
from typing import Protocol

from rostools.bag.live.snapshot_job import SnapshotJob
from rostools.bag.live.snapshot_srv import SnapshotRequest, encode_answer
from rostools.errors import RostoolsError
from rostools.msgs.wellknown import SET_BOOL, STRING, TRIGGER, TRIGGER_SNAPSHOT
from rostools.node.node import LiveNode
from rostools.selection import Selection

#: The topic each complete file is announced on, private to the node.
WRITTEN = "~written"


class Served(Protocol):
    """What the services steer: ``snapshot.Snapshotter``."""

    node: LiveNode
    selection: Selection
    announce: Callable[[SnapshotJob], None] | None

    def trigger(self, request: SnapshotRequest, remote: bool = True) -> SnapshotJob:
        """Start a snapshot."""

    def local_request(self) -> SnapshotRequest:
        """The window of a local trigger."""

    def set_paused(self, paused: bool) -> bool:
        """Pause or resume buffering."""

    def stop_open_ended(self) -> int:
        """End the files written until stopped."""


async def serve(snap: Served) -> None:
    """Advertise the services and ``~written`` on the snapshotter's node."""
    node = snap.node
    written = await node.advertise(WRITTEN, STRING)
    # -a must not buffer our own announcements
    snap.selection.exclude.append(re.compile(re.escape(written.topic)))

    def announce(job: SnapshotJob) -> None:
        text = json.dumps(job.summary()).encode()
        written.publish_raw(struct.pack("<I", len(text)) + text)

    def trigger_snapshot(request: bytes) -> bytes:
        try:
            job = snap.trigger(SnapshotRequest.decode(request))
        except RostoolsError as err:
            return encode_answer(False, str(err))
        return encode_answer(True, str(job.path))

    def trigger(_: bytes) -> bytes:
        try:
            job = snap.trigger(snap.local_request(), remote=False)
        except RostoolsError as err:
            return encode_answer(False, str(err))
        return encode_answer(True, str(job.path))

    def pausing(paused: bool) -> bytes:
        word = "paused" if paused else "resumed"
        if snap.set_paused(paused):
            return encode_answer(True, f"buffering {word}")
        return encode_answer(False, f"buffering is already {word}")

    def enable(request: bytes) -> bytes:
        return pausing(request[:1] in (b"", b"\x00"))

    def stop(_: bytes) -> bytes:
        ended = snap.stop_open_ended()
        return encode_answer(ended > 0, f"{ended} open-ended snapshot(s) ended")

    await node.advertise_service("trigger_snapshot", TRIGGER_SNAPSHOT, trigger_snapshot)
    await node.advertise_service("enable_snapshot", SET_BOOL, enable)
    await node.advertise_service("~trigger", TRIGGER, trigger)
    await node.advertise_service("~pause", TRIGGER, lambda _: pausing(True))
    await node.advertise_service("~resume", TRIGGER, lambda _: pausing(False))
    await node.advertise_service("~stop", TRIGGER, stop)
    # last: ``announce`` set is how the API and the tests know every service can be called
    snap.announce = announce
