"""The well-known types rostools speaks itself: each md5sum is its definition's."""

from __future__ import annotations

from pathlib import Path

import pytest

from rostools.msgs import wellknown
from rostools.msgs.store import BuiltinSource, PathSource, TypeStore, md5_of
from rostools.msgs.topictype import ServiceType, TopicType
from rostools.msgs.wellknown import (
    CLOCK,
    SET_BOOL,
    STRING,
    TRIGGER,
    TRIGGER_SNAPSHOT,
    TRIGGER_SNAPSHOT_TEXT,
)

BUILTIN = TypeStore([BuiltinSource()])


@pytest.mark.parametrize("known", [STRING, CLOCK], ids=lambda t: t.type)
def test_message_types_match_their_definitions(known: TopicType) -> None:
    assert BUILTIN.md5(known.type) == known.md5sum
    assert md5_of(known.type, known.definition) == known.md5sum


@pytest.mark.parametrize("known", [TRIGGER, SET_BOOL], ids=lambda t: t.type)
def test_service_types_match_their_definitions(known: ServiceType) -> None:
    assert BUILTIN.srv_md5(known.type) == known.md5sum


def test_trigger_snapshot_is_rosbag_snapshots(tmp_path: Path) -> None:
    package = tmp_path / "rosbag_snapshot_msgs"
    (package / "srv").mkdir(parents=True)
    (package / "package.xml").write_text("<package><name>rosbag_snapshot_msgs</name></package>")
    (package / "srv" / "TriggerSnapshot.srv").write_text(TRIGGER_SNAPSHOT_TEXT)
    store = TypeStore([PathSource([tmp_path])])
    assert store.srv_md5(TRIGGER_SNAPSHOT.type) == TRIGGER_SNAPSHOT.md5sum
    # as genmsg computes it for the .srv of ros/rosbag_snapshot (1.0.6)
    assert TRIGGER_SNAPSHOT.md5sum == "d5f2b150730729bd0435527e829e65e2"


def test_every_well_known_type_is_checked_here() -> None:
    """A type added to the module is added to the checks above."""
    known = {
        name
        for name, value in vars(wellknown).items()
        if isinstance(value, TopicType | ServiceType)
    }
    assert known == {"STRING", "CLOCK", "TRIGGER", "SET_BOOL", "TRIGGER_SNAPSHOT"}
