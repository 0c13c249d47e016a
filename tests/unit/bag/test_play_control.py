"""``bag play``'s controls: the rate-control topic, ``~pause_playback``, the status line."""

from __future__ import annotations

import struct

import pytest

from rostools.bag.live.play_control import RateControl, header_first, set_bool_reply
from rostools.bag.live.player import State, Status
from rostools.cli.bag.play import status_line
from rostools.msgs.store import TypeStore
from rostools.msgs.topictype import ServiceType


def test_set_bool_type_is_std_srvs() -> None:
    from rostools.msgs.wellknown import SET_BOOL

    assert ServiceType.of(TypeStore.default(), "std_srvs/SetBool") == SET_BOOL


@pytest.mark.parametrize(
    ("definition", "expected"),
    [
        ("# comment\n\nHeader header\nfloat64 x\n", True),
        ("# a comment # with two marks\nHeader header\n", True),
        ("std_msgs/Header header  # spelt out\n", True),
        ("uint32 seq\ntime stamp\nstring frame_id\n", False),  # a Header itself: no header
        ("float64 x\nHeader header\n", False),
        ("", False),
    ],
)
def test_header_first(definition: str, expected: bool) -> None:
    assert header_first(definition) is expected


def reply(data: bytes) -> tuple[bool, str]:
    success, size = struct.unpack_from("<?I", data)
    return success, data[5 : 5 + size].decode()


@pytest.mark.parametrize(
    ("request_", "paused", "answer", "change"),
    [
        (b"\x01", False, (True, "Playback is now paused"), [True]),
        (b"\x01", True, (False, "Bag is already paused."), []),
        (b"\x00", True, (True, "Playback is now resumed"), [False]),
        (b"\x00", False, (False, "Bag is already running."), []),
        (b"", True, (True, "Playback is now resumed"), [False]),  # too short: false
    ],
)
def test_pause_playback_answers_as_rosbag(
    request_: bytes, paused: bool, answer: tuple[bool, str], change: list[bool]
) -> None:
    changes: list[bool] = []
    assert reply(set_bool_reply(request_, paused, changes.append)) == answer
    assert changes == change


def test_rate_control_holds_when_stamps_lag() -> None:
    woken: list[int] = []
    control = RateControl("/ctl", 0.25, lambda: woken.append(1))
    assert not control.holds(10**12)  # not started: nothing to compare with
    control.start(100 * 10**9)
    assert not control.holds(100_250_000_000)
    assert control.holds(100_250_000_001)
    assert control.lag(100_500_000_000) == 0.5
    control.last_ns = 100_400_000_000
    assert not control.holds(100_600_000_000)
    control.start(0)  # a second start (a loop) keeps the newest stamp
    assert control.last_ns == 100_400_000_000


def test_delayed_status_line_shows_the_delay() -> None:
    line = status_line(Status(state=State.DELAYED, bag_time=100 * 10**9, total=1.0, delay=0.42))
    assert line.startswith(" [DELAYED]  Bag Time:    100.000000   Duration: 0.000000 / 1.000000")
    assert line.endswith("   Delay: 0.42 \r")
    running = status_line(Status(bag_time=100 * 10**9, total=1.0))
    assert running.startswith(" [RUNNING]") and "Delay" not in running


class _Conn:
    def __init__(self, header: dict[str, str] | None) -> None:
        self.header = header


def _stamped(secs: int, nsecs: int) -> bytes:
    return struct.pack("<III", 7, secs, nsecs)


def test_rate_control_follows_the_newest_stamp(caplog: pytest.LogCaptureFixture) -> None:
    woken: list[int] = []
    control = RateControl("/ctl", 0.5, lambda: woken.append(1))
    control.start(100 * 10**9)
    stamped = _Conn({"message_definition": "Header header\nfloat64 x\n"})
    control._frames([_stamped(101, 0), _stamped(102, 250_000_000)], stamped, 0.0)  # type: ignore[arg-type]
    assert control.last_ns == 102_250_000_000 and woken == [1]
    assert not control.holds(102_750_000_000) and control.holds(102_750_000_001)
    control._frames([b"short"], stamped, 0.0)  # type: ignore[arg-type]
    assert control.last_ns == 102_250_000_000  # too short for a stamp: ignored
    with caplog.at_level("WARNING", logger="rostools.bag.live.play_control"):
        for conn in (_Conn({"message_definition": "float64 x\n"}), _Conn({}), _Conn(None)):
            control._frames([_stamped(200, 0)], conn, 0.0)  # type: ignore[arg-type]
    assert control.last_ns == 102_250_000_000  # no Header first: not a stamp
    assert [r.getMessage() for r in caplog.records] == [
        "the rate control topic's type has no Header first; ignored"
    ]  # once
