"""``bag record`` when the disk fills up: it stops, closes the file, and keeps what it wrote."""

from __future__ import annotations

import asyncio
import struct
from pathlib import Path

import pytest

from rostools.bag import record
from rostools.bag.access import open_bag
from rostools.errors import RostoolsError
from rostools.master.server import MasterThread
from rostools.msgs.topictype import TopicType
from rostools.node.node import Node

STRING = TopicType("std_msgs/String", "992ce8a1687cec8c8bd883ec73ca41d1", "string data\n")


def test_a_filling_disk_stops_the_recording_cleanly(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    free = [10 * 1024**3]
    monkeypatch.setattr(record, "free_bytes", lambda folder: free[0])
    monkeypatch.setattr(record, "DISK_PERIOD", 0.05)
    opts = record.RecordOptions(topics=["/t"], base=tmp_path / "x.bag", min_space=1024**3)

    async def main(uri: str) -> int:
        pub_node = await Node("pub", uri).start()
        rec_node = await Node("rec", uri).start()
        try:
            pub = await pub_node.advertise("/t", STRING)
            rec = record.Recorder(rec_node, opts)
            task = asyncio.ensure_future(rec.run(asyncio.Event()))
            while pub.subscriber_count == 0:
                await asyncio.sleep(0.01)
            sent = 0
            while sent < 50 or rec.stats["/t"].written < 50:
                pub.publish_raw(struct.pack("<I", 1) + b"x")
                pub.flush()
                sent += 1
                await asyncio.sleep(0.002)
            free[0] = 512 * 1024**2  # below -L: the next check stops the recording
            with pytest.raises(RostoolsError, match=r"less than 1G free .* recording stopped"):
                await asyncio.wait_for(task, 10)
            return rec.stats["/t"].written
        finally:
            await rec_node.close()
            await pub_node.close()

    with MasterThread() as master:
        written = asyncio.run(main(master.uri))
    assert not list(tmp_path.glob("*.active"))  # closed and renamed
    with open_bag(tmp_path / "x.bag") as reader:
        assert reader.info().indexed
        assert len(list(reader.messages())) == written >= 50
