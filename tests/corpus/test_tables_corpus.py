"""Third-party bags (../shared/corpus) as Arrow tables: every value of every table of every
bag real rosbag reads is what genpy decodes. One test and one system-python run for all the
bags: genpy is the slow half, and a run per bag or per worker would cost it many times."""

from __future__ import annotations

from typing import Any

import pytest

from rostools.bag.tables.batches import table_schemas
from tests.support.env import CORPUS, needs_corpus, needs_ros1
from tests.support.tables import first_difference, genpy_view, ours

pytestmark = [needs_corpus, needs_ros1]
pytest.importorskip("pyarrow", reason="the arrow extra (in the test extra)")

ROS1 = CORPUS / "ros1"
#: Files real rosbag cannot read at all (the corpus README says why), so nothing to compare.
UNREADABLE = {
    "rosbag.js/empty-file.bag": "empty",
    "rosbag2/test.bag": "SQLite, a ROS 2 bag",
    "rosbag-rs/dummy.bag": "unindexed",
    "webviz/invalid.bag": "cut short, unindexed",
}
#: rosbag yields this bag in chunk order (2 s, 3 s, 1 s); tables are in time order.
UNSORTED = "rosbag.js/example-unsorted-chunks.bag"
#: Its one connection has an empty definition: genpy reads its messages as of no fields;
#: a table cannot know the fields, so it says so and reads nothing.
NO_DEFINITION = "webviz/bag-with-empty-message-definition.bag"


def bags() -> list[str]:
    names = sorted(str(p.relative_to(ROS1)) for p in ROS1.rglob("*.bag"))
    return [n for n in names if n not in UNREADABLE]


def differences(name: str, theirs: dict[Any, Any]) -> list[str]:
    """What our tables of one bag get wrong, against genpy's view of it."""
    if name == NO_DEFINITION:
        (entry,) = table_schemas([ROS1 / name])
        wanted = "unknown message type led_array_msgs/Status"
        return [] if entry.schema is None and wanted in str(entry.error) else [str(entry)]
    mine = ours([ROS1 / name])
    if sorted(mine) != sorted(theirs):
        return [f"tables {sorted(mine)} != {sorted(theirs)}"]
    found = []
    for key, rows in theirs.items():
        if name == UNSORTED:
            rows = sorted(rows, key=lambda row: row[0])
        if len(mine[key]) != len(rows):
            found.append(f"{key}: {len(mine[key])} rows, genpy {len(rows)}")
            continue
        for i, (a, b) in enumerate(zip(mine[key], rows, strict=True)):
            if (diff := first_difference(list(a), list(b), f"{key} row {i}")) is not None:
                found.append(diff)
                break
    return found


def test_every_value_of_every_bag_is_genpys() -> None:
    names = bags()
    view = genpy_view([ROS1 / name for name in names])
    checked = 0
    wrong = {}
    for name in names:
        theirs = view[str(ROS1 / name)]
        assert "error" not in theirs, (name, theirs)
        if found := differences(name, theirs):
            wrong[name] = found
        checked += sum(len(rows) for rows in theirs.values())
    assert not wrong, wrong
    assert len(names) >= 30 and checked > 10_000  # the corpus as it is: every bag was read
