"""Every readable corpus bag into rosbag2 (issue 39), held to rosbags-convert and rosbags' reader.

Each bag is converted once, in this process (``convert_to_ros2``), and so is rosbags-convert's
conversion of it: the CDR bytes must be the same, rosbags' rosbag2 reader must read ours, each
message must equal the ROS 1 one less ``seq``, the CRCs must hold and metadata.yaml must have
rosbag2's fields (``tests/support/ros2conv.check_output``).
"""

from __future__ import annotations

from pathlib import Path

import pytest

from rostools.bag.formats.ros2types import UnmappableTypeError
from rostools.bag.tools.ros2convert import convert_to_ros2
from tests.corpus.test_bag_corpus import DERIVED, ROS1, bags
from tests.support.env import CORPUS, needs_corpus
from tests.support.ros2conv import check_output, ros2_messages, rosbags_convert

pytestmark = needs_corpus

#: A connection with no definition and an md5sum no Noetic type has: refused, naming it
#: (rosbags-convert refuses the whole bag, even with the topic excluded).
NO_DEFINITION = {"webviz/bag-with-empty-message-definition.bag": "/led_array_status"}
#: rosbags reads ROS 1's lower-case constants (``uint8 a = 1``) as ROS 2 fields with defaults:
#: it fails on this bag, whose type has constants only; ours is ROS 2's empty message.
ROSBAGS_MISREADS = "matlab_rosbag/constants.bag"


@pytest.mark.parametrize("name", bags())
def test_corpus_bag_into_rosbag2(name: str, tmp_path: Path) -> None:
    src = ROS1 / name
    exclude = [NO_DEFINITION[name]] if name in NO_DEFINITION else []
    if exclude:
        with pytest.raises(UnmappableTypeError, match="led_array_msgs/Status"):
            convert_to_ros2(src, tmp_path / "refused")
        assert not (tmp_path / "refused").exists()
    report = convert_to_ros2(src, tmp_path / "ours", exclude=exclude)
    assert report.lost == () and report.messages_written == report.messages_read
    theirs = tmp_path / "theirs"
    if name == ROSBAGS_MISREADS:
        with pytest.raises(Exception, match="Constants"):
            rosbags_convert([src], theirs, "lyrical")
        assert ros2_messages(tmp_path / "ours")["/constants"][0][1] == b"\x00\x01\x00\x00\x00"
        return
    assert check_output([src], tmp_path / "ours", exclude=exclude) == []
    if exclude:  # rosbags-convert refuses the whole bag, excluded topic or not
        with pytest.raises(Exception, match="hash mismatch"):
            rosbags_convert([src], theirs, "lyrical", exclude)
        return
    rosbags_convert([src], theirs, "lyrical", exclude)
    ours, want = ros2_messages(tmp_path / "ours"), ros2_messages(theirs)
    assert sorted(ours) == sorted(want)
    for topic in want:
        assert sorted(ours[topic]) == sorted(want[topic]), topic


@pytest.mark.parametrize("name", sorted(DERIVED))
def test_cut_corpus_bag_converts_what_reads_and_lists_the_rest(name: str, tmp_path: Path) -> None:
    src = CORPUS / "ros1-derived" / name
    report = convert_to_ros2(src, tmp_path / "ours")
    assert report.notes and report.messages_written > 0  # read without its index
    # Cut in a chunk: what it held is listed (exit 6); cut at the index: nothing is lost.
    assert bool(report.lost) == (name == "test1_cut_at_60pct.bag")
    assert all(str(src) in line for line in report.lost + report.notes)
    assert check_output([src], tmp_path / "ours") == []
