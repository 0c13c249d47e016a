"""``bag play``'s player on a stand-in node: what it advertises, sends, when, and its controls.

Pacing is checked from below only (a message is never sent before it is due: load only makes
a send late), with an upper bound far from any load (``LATE``).
"""

from __future__ import annotations

import asyncio
import itertools
import struct
import time
from collections.abc import Awaitable, Callable, Hashable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

from rostools.bag.access import open_bag, open_writer
from rostools.bag.base import BagReader
from rostools.bag.play_control import SET_BOOL
from rostools.bag.player import CONNECT_GRACE, Player, PlayOptions, State, Status
from rostools.errors import UsageError
from rostools.node.clock import CLOCK
from tests.support.bagdata import STRING_MD5

NS = 1_000_000_000
T0 = 100 * NS
#: Far more than any wait here, however loaded the machine.
LATE = 10.0
#: How early a send may look: the clock's reading on either side of a sleep.
EARLY = 0.0005
#: A rate-control topic's type: a Header first.
STAMPED_DEF = "Header header\nfloat64 x\n"


@dataclass
class Sent:
    """One message a publisher sent."""

    at: float  # monotonic
    topic: str
    data: bytes
    source: Hashable
    keep: bool


@dataclass
class FakePublisher:
    """Records what it is asked to send; ``subscriber_count`` and ``reported`` as the test sets."""

    node: FakeNode
    name: str
    type: Any
    latch: bool
    queue_size: int
    subscriber_count: int = 0
    reported: list[str] = field(default_factory=list)
    flushed: int = 0

    def publish_raw(self, payload: bytes, source: Hashable = None, keep: bool = True) -> None:
        self.node.sent.append(Sent(time.monotonic(), self.name, bytes(payload), source, keep))

    def flush(self) -> None:
        self.flushed += 1


class FakeNode:
    """What the player asks of a live node."""

    def __init__(self) -> None:
        self.publishers: dict[str, FakePublisher] = {}
        self.services: dict[str, tuple[Any, Callable[[bytes], bytes]]] = {}
        self.subscribed: dict[str, Callable[..., None]] = {}
        self.sent: list[Sent] = []
        self.advertised_at = 0.0
        #: The subscribers the master lists for a topic when it is advertised.
        self.listed: dict[str, list[str]] = {}

    async def advertise(
        self, name: str, topic_type: Any, latch: bool = False, queue_size: int = 100
    ) -> FakePublisher:
        self.advertised_at = time.monotonic()
        pub = self.publishers[name] = FakePublisher(self, name, topic_type, latch, queue_size)
        pub.reported = list(self.listed.get(name, []))
        return pub

    async def advertise_service(
        self, name: str, kind: Any, handler: Callable[[bytes], bytes]
    ) -> None:
        self.services[name] = (kind, handler)

    async def subscribe(self, topic: str, callback: Callable[..., None]) -> None:
        self.subscribed[topic] = callback

    def texts(self, topic: str | None = None) -> list[str]:
        """The std_msgs/String texts sent (on ``topic``), in order."""
        return [s.data[4:].decode() for s in self.sent if topic in (None, s.topic)]


def string(text: str) -> bytes:
    return struct.pack("<I", len(text)) + text.encode()


def write_bag(path: Path, messages: list[tuple[str, float, str]]) -> Path:
    """A bag of (topic, seconds after T0, text); /latched and /tf are latched."""
    with open_writer(path) as writer:
        conns = {}
        for topic, _, _ in messages:
            if topic not in conns:
                conns[topic] = writer.add_connection(
                    topic,
                    "std_msgs/String",
                    STRING_MD5,
                    "string data\n",
                    callerid=f"/pub{topic}",
                    latching=topic in ("/latched", "/tf"),
                )
        for topic, secs, text in messages:
            writer.write(conns[topic], T0 + round(secs * NS), string(text))
    return path


TEN = [("/chatter", i * 0.01, f"m{i}") for i in range(10)]  # 10 messages over 90 ms


@dataclass
class Played:
    node: FakeNode
    player: Player
    count: int
    began: float
    ended: float
    shown: list[Status]
    said: list[str]


def play(
    paths: list[Path],
    during: Callable[[Player, FakeNode, asyncio.Event], Awaitable[None]] | None = None,
    node: FakeNode | None = None,
    shown: list[Status] | None = None,
    **options: Any,
) -> Played:
    """Play ``paths`` with ``options`` (no -d unless given); ``during`` runs beside it, and
    ``shown`` gets each status shown as it is."""
    options.setdefault("delay", 0.0)
    node = node or FakeNode()
    readers: list[BagReader] = [open_bag(p) for p in paths]
    player = Player(node, readers, PlayOptions(**options))  # type: ignore[arg-type]
    shown = [] if shown is None else shown
    said: list[str] = []

    def show(status: Status) -> None:
        shown.append(Status(**vars(status)))

    async def main() -> int:
        stop = asyncio.Event()
        task = None
        if during is not None:
            task = asyncio.get_running_loop().create_task(during(player, node, stop))
        count = await asyncio.wait_for(player.run(stop, show, said.append), LATE)
        if task is not None:
            await asyncio.wait_for(task, LATE)
        return count

    began = time.monotonic()
    try:
        count = asyncio.run(main())
    finally:
        for reader in readers:
            reader.close()
    return Played(node, player, count, began, time.monotonic(), shown, said)


async def until(check: Callable[[], bool]) -> None:
    """Until ``check`` holds (awaited, never slept for; the test's LATE bounds it)."""
    while not check():
        await asyncio.sleep(0.001)


def assert_paced(sent: list[Sent], times: list[float], rate: float, start: float) -> None:
    """No message before its time: ``start`` (at or before the first was due) plus its bag
    time (s, from the first) / rate."""
    assert len(sent) == len(times)
    for s, t in zip(sent, times, strict=True):
        assert s.at >= start + (t - times[0]) / rate - EARLY, (s.topic, t)


def test_each_topic_gets_one_publisher_as_recorded(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", [("/chatter", 0, "a"), ("/tf", 0.1, "b")])
    other = write_bag(tmp_path / "b.bag", [("/tf", 0.2, "c"), ("/chatter", 0.3, "d")])
    played = play([bag, other], immediate=True, prefix="/replay", queue_size=7)
    pubs = played.node.publishers
    assert set(pubs) == {"/replay/chatter", "/replay/tf"}
    assert pubs["/replay/tf"].latch and not pubs["/replay/chatter"].latch
    assert pubs["/replay/chatter"].queue_size == 7
    kind = pubs["/replay/chatter"].type
    assert (kind.type, kind.md5sum, kind.definition) == (
        "std_msgs/String",
        STRING_MD5,
        "string data\n",
    )
    assert played.node.services["~pause_playback"][0] == SET_BOOL
    assert played.node.texts() == ["a", "b", "c", "d"]  # the bags merged in time order
    assert [s.source for s in played.node.sent] == [
        ("/chatter", "/pub/chatter"),
        ("/tf", "/pub/tf"),
        ("/tf", "/pub/tf"),
        ("/chatter", "/pub/chatter"),
    ]
    assert [s.keep for s in played.node.sent] == [False, True, True, False]
    assert all(p.flushed for p in pubs.values())  # each send is written at once
    assert played.count == played.player.status.published == 4


def test_a_latched_connection_makes_its_topic_latched(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", [("/chatter", 0, "a")])
    with open_writer(tmp_path / "b.bag") as writer:
        conn = writer.add_connection(
            "/chatter", "std_msgs/String", STRING_MD5, "string data\n", callerid="/l", latching=True
        )
        writer.write(conn, T0 + 1, string("b"))
    for order in ([bag, tmp_path / "b.bag"], [tmp_path / "b.bag", bag]):
        assert play(order, immediate=True).node.publishers["/chatter"].latch


def test_messages_go_out_at_their_recorded_pace(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", TEN)
    played = play([bag], rate=0.5)
    assert played.node.texts() == [f"m{i}" for i in range(10)]
    assert_paced(played.node.sent, [i * 0.01 for i in range(10)], 0.5, played.began)
    assert played.ended - played.began < 0.18 + LATE


def test_play_starts_with_the_first_message_in_the_window(tmp_path: Path) -> None:
    """-s into a gap: the first message played goes at once, the next at their pace."""
    bag = write_bag(
        tmp_path / "a.bag", [("/chatter", 0, "a"), ("/chatter", 3.0, "b"), ("/chatter", 3.2, "c")]
    )
    played = play([bag], start=0.1)
    b, c = played.node.sent
    assert b.at - played.began < 2.0  # not the 2.9 s of bag time before it
    assert c.at >= b.at + 0.2 - 0.01  # c is timed from b (b was due when it was read)


def test_the_pace_is_the_recordings_not_slower(tmp_path: Path) -> None:
    """A second of bag is a second of play: the last message is due one second after the first
    (a late send does not delay the next: each is timed from the start)."""
    bag = write_bag(tmp_path / "a.bag", [("/chatter", 0, "a"), ("/chatter", 1.0, "b")])
    a, b = play([bag]).node.sent
    assert 1.0 - EARLY <= b.at - a.at < 1.6


def test_a_rate_plays_faster(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", [("/chatter", 0, "a"), ("/chatter", 2.0, "b")])
    played = play([bag], rate=10)
    first, second = played.node.sent
    assert second.at >= played.began + 0.2 - EARLY
    assert second.at - first.at < 2.0  # not at the recorded pace


def test_start_and_duration_choose_the_messages_and_send_the_latched_before(
    tmp_path: Path,
) -> None:
    """-s: what a late subscriber would still get (the last latched message) goes first."""
    messages = [("/latched", 0, "old"), ("/latched", 0.02, "last"), *TEN[1:]]
    bag = write_bag(tmp_path / "a.bag", messages)
    played = play([bag], immediate=True, start=0.035, duration=0.03)
    assert played.node.texts() == ["last", "m4", "m5", "m6"]
    assert played.node.sent[0].source == ("/latched", "/pub/latched")
    assert played.player.status.total == pytest.approx(0.03)
    whole = play([bag], immediate=True)
    assert whole.node.texts() == ["old", "m1", "last", *[f"m{i}" for i in range(2, 10)]]
    topics = play([bag], immediate=True, topics=["/chatter"], start=0.035)
    assert topics.node.texts() == ["m4", "m5", "m6", "m7", "m8", "m9"]
    assert set(topics.node.publishers) == {"/chatter"}
    assert play([bag], immediate=True, topics=["/latched"]).node.texts() == ["old", "last"]


def test_the_status_spans_the_messages_played(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", [("/other", 0, "o"), *TEN[1:9], ("/other", 0.5, "o2")])
    readers = [open_bag(bag)]
    try:
        whole = Player(FakeNode(), readers, PlayOptions())  # type: ignore[arg-type]
        whole.measure()
        assert (whole.shown_from, whole.shown_until) == (T0, T0 + NS // 2)
        assert whole.status.total == 0.5
        some = Player(FakeNode(), readers, PlayOptions(topics=["/chatter"], start=0.015))  # type: ignore[arg-type]
        some.measure()
        assert (some.shown_from, some.shown_until) == (T0 + 2 * NS // 100, T0 + 8 * NS // 100)
        assert some.status.total == pytest.approx(0.06)
        cut = Player(FakeNode(), readers, PlayOptions(duration=0.055))  # type: ignore[arg-type]
        cut.measure()
        assert (cut.shown_from, cut.shown_until) == (T0, T0 + 5 * NS // 100)
        none = Player(FakeNode(), readers, PlayOptions(topics=["/chatter"], start=0.3))  # type: ignore[arg-type]
        none.measure()
        assert (none.shown_from, none.shown_until) == (none.from_ns, none.until_ns)
        exact = Player(FakeNode(), readers, PlayOptions(duration=0.08))  # type: ignore[arg-type]
        exact.measure()  # -u ending on a message keeps it
        assert exact.shown_until == T0 + 8 * NS // 100
        late = Player(FakeNode(), readers, PlayOptions(start=0.015))  # type: ignore[arg-type]
        late.measure()  # -s alone: from the first message at or after it, to the bags' end
        assert (late.shown_from, late.shown_until) == (T0 + 2 * NS // 100, T0 + NS // 2)
        past = Player(FakeNode(), readers, PlayOptions(start=10.0))  # type: ignore[arg-type]
        past.measure()  # -s past the end: nothing plays
        assert past.status.total == 0.0
    finally:
        readers[0].close()


def test_the_status_spans_several_bags(tmp_path: Path) -> None:
    long = write_bag(tmp_path / "long.bag", [("/chatter", 0, "a"), ("/chatter", 0.5, "b")])
    short = write_bag(tmp_path / "short.bag", [("/chatter", 0.1, "c")])
    readers = [open_bag(long), open_bag(short)]
    try:
        player = Player(FakeNode(), readers, PlayOptions(topics=["/chatter"]))  # type: ignore[arg-type]
        player.measure()
        assert (player.shown_from, player.shown_until) == (T0, T0 + NS // 2)
    finally:
        for reader in readers:
            reader.close()


def test_an_empty_bag_plays_nothing(tmp_path: Path) -> None:
    with open_writer(tmp_path / "empty.bag"):
        pass
    played = play([tmp_path / "empty.bag"])
    assert played.count == 0 and not played.node.sent
    assert (played.player.status.total, played.player.status.bag_time) == (0.0, 0)
    past = play([write_bag(tmp_path / "a.bag", TEN)], start=5.0)
    assert past.count == 0 and past.player.status.total == 0.0


def test_the_bag_time_playing_is_paced_by_the_rate(tmp_path: Path) -> None:
    """The status line's and /clock's bag time: from -s, at the rate, never past the next."""
    bag = write_bag(tmp_path / "a.bag", TEN)
    readers = [open_bag(bag)]
    try:
        player = Player(FakeNode(), readers, PlayOptions(rate=2.0, start=0.01))  # type: ignore[arg-type]
        player._origin = 50.0
        assert player._bag_time(50.25, T0 + 10 * NS) == T0 + NS // 100 + NS // 2
        assert player._bag_time(50.25, T0 + NS // 10) == T0 + NS // 10
    finally:
        readers[0].close()


def test_the_end_shows_done_at_the_last_time(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", TEN)
    played = play([bag], rate=0.5)
    last = played.shown[-1]
    assert last.state is State.DONE and last.published == 10
    assert last.bag_time == T0 + 9 * NS // 100
    assert last.elapsed == last.total == pytest.approx(0.09)
    during = [s for s in played.shown if s.state is State.RUNNING]
    assert during, "the status is shown while playing"
    for s in during:
        assert T0 <= s.bag_time <= T0 + 9 * NS // 100
        assert s.elapsed == pytest.approx((s.bag_time - T0) / NS)


def test_the_status_is_refreshed_ten_times_a_second(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", [("/chatter", 0, "a"), ("/chatter", 0.5, "b")])
    played = play([bag])
    running = [s for s in played.shown if s.state is State.RUNNING]
    assert len(running) >= 3  # some 5 in the 0.5 s gap
    assert len(running) <= (played.ended - played.began) / 0.1 + 3


def test_a_loop_plays_again_until_stopped(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", TEN[:3])

    async def stop_after_three_rounds(player: Player, node: FakeNode, stop: asyncio.Event) -> None:
        await until(lambda: len(node.sent) >= 9)
        stop.set()

    played = play([bag], stop_after_three_rounds, loop=True, rate=4)
    assert played.node.texts()[:9] == ["m0", "m1", "m2"] * 3
    assert played.count == len(played.node.sent)


def test_stopping_ends_the_play_at_once(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", [("/chatter", 0, "a"), ("/chatter", 60, "b")])

    async def stop_after_the_first(player: Player, node: FakeNode, stop: asyncio.Event) -> None:
        await until(lambda: len(node.sent) == 1)
        stop.set()

    played = play([bag], stop_after_the_first)
    assert played.node.texts() == ["a"] and played.count == 1
    assert played.ended - played.began < LATE


def test_a_stopped_play_shows_the_last_message_sent(tmp_path: Path) -> None:
    many = [("/chatter", i * 0.001, f"m{i}") for i in range(3000)]
    bag = write_bag(tmp_path / "a.bag", many)

    async def stop_soon(player: Player, node: FakeNode, stop: asyncio.Event) -> None:
        await until(lambda: len(node.sent) > 0)
        stop.set()

    played = play([bag], stop_soon, immediate=True)
    assert 0 < played.count < 3000
    last = played.shown[-1]
    assert last.state is State.DONE
    assert last.bag_time == T0 + round((played.count - 1) * 0.001 * NS)


def test_play_without_a_status_line(tmp_path: Path) -> None:
    """-q: no status shown, the messages as paced."""
    bag = write_bag(tmp_path / "a.bag", TEN[:3])
    node = FakeNode()
    with open_bag(bag) as reader:
        player = Player(node, [reader], PlayOptions(delay=0.0, clock=True))  # type: ignore[arg-type]

        async def main() -> int:
            return await asyncio.wait_for(player.run(asyncio.Event()), LATE)

        assert asyncio.run(main()) == 3
    assert node.texts("/chatter") == ["m0", "m1", "m2"]


def test_keep_alive_waits_for_the_stop(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", TEN[:1])
    stopped_at: list[float] = []

    async def stop_later(player: Player, node: FakeNode, stop: asyncio.Event) -> None:
        await until(lambda: player.status.state is State.DONE)
        await asyncio.sleep(0.05)
        stopped_at.append(time.monotonic())
        stop.set()

    played = play([bag], stop_later, keep_alive=True)
    assert played.ended >= stopped_at[0]


def test_a_paused_start_waits_and_a_step_sends_one(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", TEN[:4])
    stepped: list[float] = []

    async def steer(player: Player, node: FakeNode, stop: asyncio.Event) -> None:
        await asyncio.sleep(0.05)
        assert not node.sent and player.status.state is State.PAUSED
        stepped.append(time.monotonic())
        player.step()
        await until(lambda: len(node.sent) == 1)
        await asyncio.sleep(0.05)
        assert len(node.sent) == 1  # still paused
        player.toggle_pause()
        assert player.status.state is State.RUNNING
        player.step()  # not paused: no step is kept for later
        assert player.steps == 0

    played = play([bag], steer, pause=True)
    assert played.node.texts() == ["m0", "m1", "m2", "m3"]
    # the step sent m0 then; the rest follow at their pace from there
    assert_paced(played.node.sent, [0.0, 0.01, 0.02, 0.03], 1.0, stepped[0])


def test_steps_send_at_once_and_the_rest_follows_from_the_last(tmp_path: Path) -> None:
    bag = write_bag(
        tmp_path / "a.bag", [("/chatter", 0, "a"), ("/chatter", 2.0, "b"), ("/chatter", 2.1, "c")]
    )
    stepped: list[float] = []

    async def steer(player: Player, node: FakeNode, stop: asyncio.Event) -> None:
        player.step()
        player.step()  # two presses of ``s``: two messages
        await until(lambda: len(node.sent) == 2)
        stepped.append(time.monotonic())
        player.toggle_pause()

    played = play([bag], steer, pause=True)
    a, b, c = played.node.sent
    assert b.at - a.at < 2.0  # a step does not wait for the message's time
    assert c.at >= b.at + 0.1 - 0.01 and c.at - stepped[0] < 2.0


def test_paused_time_does_not_count(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", [("/chatter", 0, "a"), ("/chatter", 0.4, "b")])
    paused: list[float] = []

    async def pause_between(player: Player, node: FakeNode, stop: asyncio.Event) -> None:
        await until(lambda: len(node.sent) == 1)
        paused.append(time.monotonic())
        player.set_paused(True)
        await asyncio.sleep(0.3)
        assert len(node.sent) == 1
        paused.append(time.monotonic())
        player.set_paused(False)

    played = play([bag], pause_between)
    a, b = played.node.sent
    # b follows a by its 0.4 s and the pause (less what the loop took to see the pause)
    assert b.at - a.at >= 0.4 + (paused[1] - paused[0]) - 0.1


def test_the_status_shows_a_pause_and_a_stop_while_paused_sends_nothing(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", [("/chatter", 0, "a"), ("/chatter", 0.5, "b")])
    shown: list[Status] = []
    node = FakeNode()

    async def pause_then_stop(player: Player, stop: asyncio.Event) -> None:
        await until(lambda: len(node.sent) == 1)
        before = len(shown)
        player.set_paused(True)
        await until(lambda: any(s.state is State.PAUSED for s in shown[before:]))
        stop.set()

    with open_bag(bag) as reader:
        player = Player(node, [reader], PlayOptions(delay=0.0))  # type: ignore[arg-type]

        async def main() -> None:
            stop = asyncio.Event()
            task = asyncio.get_running_loop().create_task(pause_then_stop(player, stop))
            await asyncio.wait_for(
                player.run(stop, lambda s: shown.append(Status(**vars(s)))), LATE
            )
            await task

        asyncio.run(main())
    assert node.texts() == ["a"]


def test_pause_topics_pause_before_their_messages(tmp_path: Path) -> None:
    bag = write_bag(
        tmp_path / "a.bag", [("/chatter", 0, "a"), ("/tf", 0.01, "t"), ("/chatter", 0.02, "b")]
    )

    async def steer(player: Player, node: FakeNode, stop: asyncio.Event) -> None:
        await until(lambda: player.status.state is State.PAUSED)
        assert node.texts() == ["a"]
        player.step()  # ``s`` sends it
        await until(lambda: len(node.sent) == 2)
        player.set_paused(False)

    played = play([bag], steer, pause_topics=["/tf"])
    assert played.node.texts() == ["a", "t", "b"]

    async def toggle_first(player: Player, node: FakeNode, stop: asyncio.Event) -> None:
        player.toggle_pause_topics()  # ``t``: they pause no more

    assert play([bag], toggle_first, pause_topics=["/tf"]).node.texts() == ["a", "t", "b"]


def test_the_keys_toggle(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", TEN[:1])
    with open_bag(bag) as reader:
        player = Player(FakeNode(), [reader], PlayOptions(pause_topics=["/tf"]))  # type: ignore[arg-type]
        player.toggle_pause()
        assert player.status.state is State.PAUSED
        player.toggle_pause()
        assert player.status.state is State.RUNNING
        player.toggle_pause_topics()
        player.toggle_pause_topics()
        assert player.pausing_on_topics


def test_the_pause_service_pauses_and_resumes(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", [("/chatter", 0, "a"), ("/chatter", 0.5, "b")])
    answers: list[bytes] = []

    async def steer(player: Player, node: FakeNode, stop: asyncio.Event) -> None:
        await until(lambda: len(node.sent) == 1)
        handler = node.services["~pause_playback"][1]
        answers.append(handler(b"\x01"))
        assert player.status.state is State.PAUSED
        answers.append(handler(b"\x01"))
        await asyncio.sleep(0.1)
        assert len(node.sent) == 1
        answers.append(handler(b"\x00"))

    played = play([bag], steer)
    assert played.node.texts() == ["a", "b"]
    assert [a[:1] for a in answers] == [b"\x01", b"\x00", b"\x01"]  # changed, not, changed
    assert b"already paused" in answers[1]


def test_a_finished_play_stays_done_when_paused(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", TEN[:1])
    played = play([bag], immediate=True)
    played.player.set_paused(True)
    assert played.player.status.state is State.DONE


def test_play_waits_for_the_delay_and_says_so(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", TEN[:1])
    played = play([bag], delay=0.1)
    assert played.node.sent[0].at >= played.node.advertised_at + 0.1 - EARLY
    assert played.said == ["Waiting 0.1 seconds after advertising topics... done.\n"]


def test_play_waits_for_subscribers_when_asked(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", [("/chatter", 0, "a"), ("/tf", 0, "b")])
    connected: list[float] = []

    async def connect(player: Player, node: FakeNode, stop: asyncio.Event) -> None:
        await until(lambda: len(node.publishers) == 2)
        await asyncio.sleep(0.05)
        node.publishers["/chatter"].subscriber_count = 1
        await asyncio.sleep(0.05)
        assert not node.sent  # /tf has none yet
        connected.append(time.monotonic())
        node.publishers["/tf"].subscriber_count = 1

    played = play([bag], connect, wait_for_subscribers=True)
    assert played.node.sent[0].at >= connected[0]
    assert played.said[:2] == ["Waiting for subscribers.\n", "Finished waiting for subscribers.\n"]


def test_play_waits_for_the_subscribers_the_master_listed(tmp_path: Path) -> None:
    """A roscpp subscriber connects some 250 ms after it is listed: its first message waits."""
    bag = write_bag(tmp_path / "a.bag", TEN[:1])
    node = FakeNode()
    node.listed["/chatter"] = ["/listener"]
    connected: list[float] = []

    async def connect(player: Player, node: FakeNode, stop: asyncio.Event) -> None:
        await until(lambda: "/chatter" in node.publishers)
        await asyncio.sleep(0.1)
        connected.append(time.monotonic())
        node.publishers["/chatter"].subscriber_count = 1

    played = play([bag], connect, node=node)
    assert played.node.sent[0].at >= connected[0]
    assert played.node.sent[0].at < played.node.advertised_at + CONNECT_GRACE + LATE


def test_a_listed_subscriber_that_never_connects_holds_play_a_while_only(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", TEN[:1])
    node = FakeNode()
    node.listed["/chatter"] = ["/dead"]
    played = play([bag], node=node)
    assert played.node.sent[0].at >= played.node.advertised_at + CONNECT_GRACE - EARLY


def test_a_long_gap_is_skipped_when_asked(tmp_path: Path) -> None:
    """--skip-empty is bag time: at -r 2, a gap of 8 s of bag is jumped, 1 s is not."""
    bag = write_bag(
        tmp_path / "a.bag",
        [
            ("/chatter", 0, "a"),
            ("/chatter", 1.0, "b"),
            ("/chatter", 9.0, "c"),
            ("/chatter", 9.4, "d"),
        ],
    )
    played = play([bag], skip_empty=2.0, rate=2.0)
    _, b, c, d = played.node.sent
    assert b.at >= played.began + 0.5 - EARLY  # a short gap is played
    assert c.at - b.at < 2.0  # 4 s at -r 2 are not
    assert d.at >= c.at + 0.2 - 0.01  # after the jump, the pace goes on


def test_the_clock_ticks_at_hz_through_a_gap(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", [("/chatter", 0, "a"), ("/chatter", 0.5, "b")])
    played = play([bag], clock=True, hz=50)
    ticks = [s.at for s in played.node.sent if s.topic == "/clock"]
    assert len(ticks) >= 12  # some 25 in the 0.5 s gap, each timed by itself
    gaps = sorted(b - a for a, b in itertools.pairwise(ticks))
    assert gaps[len(gaps) // 2] < 0.03  # a median of 20 ms: --hz 50


def test_the_clock_follows_bag_time(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", [("/chatter", 0, "a"), ("/chatter", 0.3, "b")])
    played = play([bag], clock=True, hz=50)
    clock = played.node.publishers["/clock"]
    assert clock.type == CLOCK and clock.queue_size == 1
    ticks = [s for s in played.node.sent if s.topic == "/clock"]
    times = [a * NS + b for a, b in (struct.unpack("<II", s.data) for s in ticks)]
    assert times == sorted(times) and times[0] >= T0 and times[-1] == T0 + 3 * NS // 10
    assert len(ticks) >= 5  # every 20 ms of the 0.3 s gap, however late
    assert len(ticks) <= (played.ended - played.began) / 0.02 + 2  # no more often than --hz
    sent_b = next(s.at for s in played.node.sent if s.data == string("b"))
    assert all(t <= T0 + 3 * NS // 10 for t, s in zip(times, ticks, strict=True) if s.at < sent_b)


def test_the_rate_control_topic_holds_play_until_its_stamps_catch_up(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", [("/chatter", 0, "a"), ("/chatter", 0.3, "b")])
    delays: list[float] = []

    async def stamps(player: Player, node: FakeNode, stop: asyncio.Event) -> None:
        await until(lambda: player.status.state is State.DELAYED)
        delays.append(player.status.delay)
        await until(lambda: any(s.state is State.DELAYED for s in shown))  # the status says so
        assert node.texts() == ["a"]
        conn = type("Conn", (), {"header": {"message_definition": STAMPED_DEF}})()
        stamp = T0 + 3 * NS // 10
        frame = struct.pack("<III", 0, stamp // NS, stamp % NS)
        node.subscribed["/ctl"]([frame], conn, 0.0)

    shown: list[Status] = []
    played = play([bag], stamps, rate_control_topic="/ctl", rate_control_max_delay=0.1, shown=shown)
    assert played.node.texts() == ["a", "b"]
    assert delays and 0.1 < delays[0] <= 0.3
    assert played.player.status.state is State.DONE


def test_time_held_by_the_rate_control_topic_does_not_count(tmp_path: Path) -> None:
    bag = write_bag(
        tmp_path / "a.bag", [("/chatter", 0, "a"), ("/chatter", 0.3, "b"), ("/chatter", 0.6, "c")]
    )
    conn = type("Conn", (), {"header": {"message_definition": STAMPED_DEF}})()

    async def stamps(player: Player, node: FakeNode, stop: asyncio.Event) -> None:
        await until(lambda: player.status.state is State.DELAYED)
        await asyncio.sleep(0.3)
        stamp = T0 + 10 * NS  # far ahead: nothing is held again
        node.subscribed["/ctl"]([struct.pack("<III", 0, stamp // NS, stamp % NS)], conn, 0.0)

    played = play([bag], stamps, rate_control_topic="/ctl", rate_control_max_delay=0.1)
    _, b, c = played.node.sent
    assert c.at >= b.at + 0.3 - 0.01  # the hold moved c on with b
    after = [
        s for s in played.shown if s.state is not State.DONE and s.bag_time > T0 + 3 * NS // 10
    ]
    assert after and all(s.state is State.RUNNING for s in after)


def test_a_stop_while_held_sends_nothing_more(tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", [("/chatter", 0, "a"), ("/chatter", 0.3, "b")])

    async def stop_when_held(player: Player, node: FakeNode, stop: asyncio.Event) -> None:
        await until(lambda: player.status.state is State.DELAYED)
        stop.set()

    played = play([bag], stop_when_held, rate_control_topic="/ctl", rate_control_max_delay=0.1)
    assert played.node.texts() == ["a"]


@pytest.mark.parametrize(
    ("options", "why"),
    [
        ({"rate": 0.0}, "the rate (-r) must be positive"),
        ({"clock": True, "hz": 0.0}, "--hz must be positive"),
    ],
)
def test_options_that_cannot_play_are_usage_errors(
    tmp_path: Path, options: dict[str, Any], why: str
) -> None:
    bag = write_bag(tmp_path / "a.bag", TEN[:1])
    with open_bag(bag) as reader, pytest.raises(UsageError) as refused:
        Player(FakeNode(), [reader], PlayOptions(**options))  # type: ignore[arg-type]
    assert str(refused.value) == why
    with open_bag(bag) as reader:  # --hz alone is not checked without --clock
        Player(FakeNode(), [reader], PlayOptions(hz=0.0))  # type: ignore[arg-type]
        Player(FakeNode(), [reader], PlayOptions(clock=True, hz=0.5))  # type: ignore[arg-type]
