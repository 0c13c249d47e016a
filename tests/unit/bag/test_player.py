"""``bag play``'s player on a stand-in node: what it advertises, sends, when, and its controls.

Time is virtual (``VirtualTime``): the player's clock, its sleeps and its waits are the test's,
so every send time is exact, whatever the machine's load, and a test of seconds of bag time
takes milliseconds. The keys, services and stamps a user would send are actions at given
virtual times.
"""

from __future__ import annotations

import asyncio
import math
import struct
from collections.abc import Awaitable, Callable, Coroutine, Hashable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pytest

from rostools.bag.formats.access import open_bag, open_writer
from rostools.bag.formats.base import BagReader
from rostools.bag.live import player as player_module
from rostools.bag.live.player import CONNECT_GRACE, Player, PlayOptions, State, Status
from rostools.errors import UsageError
from rostools.msgs.wellknown import CLOCK, SET_BOOL
from tests.support.bagdata import STRING_MD5

NS = 1_000_000_000
T0 = 100 * NS
#: Where virtual time starts (monotonic seconds).
START = 1000.0
#: Virtual seconds after which a player is taken to wait forever.
RUNAWAY = 1000.0
#: A rate-control topic's type: a Header first.
STAMPED_DEF = "Header header\nfloat64 x\n"


class VirtualTime:
    """The player's ``time`` and ``first``: a clock that moves only when the player waits.

    ``at(seconds, action)`` runs ``action`` once virtual time reaches ``START + seconds``, in
    the middle of whatever wait covers it; a wait ends early when an event it waits for is
    set, as ``session.first`` does.
    """

    def __init__(self) -> None:
        self.t = START
        self.actions: list[tuple[float, Callable[[], None]]] = []

    def monotonic(self) -> float:
        return self.t

    def at(self, seconds: float, action: Callable[[], None]) -> None:
        self.actions.append((START + seconds, action))
        self.actions.sort(key=lambda a: a[0])

    def _advance(self, until: float, events: list[asyncio.Event]) -> None:
        while self.actions and self.actions[0][0] <= until:
            when, action = self.actions.pop(0)
            self.t = max(self.t, when)
            action()
            if any(e.is_set() for e in events):
                return
        if until == math.inf:
            raise AssertionError("the player waits for ever")
        self.t = max(self.t, until)
        if self.t > START + RUNAWAY:
            raise AssertionError("virtual time ran away")

    def sleep(self, seconds: float) -> None:
        self._advance(self.t + max(seconds, 0.0), [])

    async def first(
        self, *waits: Coroutine[Any, Any, Any], timeout: float | None = None
    ) -> int | None:
        events: list[asyncio.Event] = [w.cr_frame.f_locals["self"] for w in waits]
        for w in waits:
            w.close()
        await asyncio.sleep(0)
        if not any(e.is_set() for e in events):
            self._advance(math.inf if timeout is None else self.t + timeout, events)
        return next((i for i, e in enumerate(events) if e.is_set()), None)


@pytest.fixture
def vt(monkeypatch: pytest.MonkeyPatch) -> VirtualTime:
    virtual = VirtualTime()
    monkeypatch.setattr(player_module, "time", virtual)
    monkeypatch.setattr(player_module, "first", virtual.first)
    return virtual


@dataclass
class Sent:
    """One message a publisher sent."""

    at: float  # virtual seconds since START
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
        at = self.node.clock() - START
        self.node.sent.append(Sent(at, self.name, bytes(payload), source, keep))

    def flush(self) -> None:
        self.flushed += 1


class FakeNode:
    """What the player asks of a live node."""

    def __init__(self, clock: Callable[[], float]) -> None:
        self.clock = clock
        self.publishers: dict[str, FakePublisher] = {}
        self.services: dict[str, tuple[Any, Callable[[bytes], bytes]]] = {}
        self.subscribed: dict[str, Callable[..., None]] = {}
        self.sent: list[Sent] = []
        #: The subscribers the master lists for a topic when it is advertised.
        self.listed: dict[str, list[str]] = {}

    async def advertise(
        self, name: str, topic_type: Any, latch: bool = False, queue_size: int = 100
    ) -> FakePublisher:
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

    def times(self, topic: str = "/chatter") -> list[float]:
        """When each message on ``topic`` was sent (virtual seconds)."""
        return [s.at for s in self.sent if s.topic == topic]


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
    ended: float  # virtual seconds since START
    shown: list[tuple[float, Status]]
    said: list[str]


def play(
    vt: VirtualTime,
    paths: list[Path],
    actions: list[tuple[float, Callable[[Player, FakeNode, asyncio.Event], object]]] = (),  # type: ignore[assignment]
    node: FakeNode | None = None,
    during: Callable[[Player, FakeNode, asyncio.Event], Awaitable[None]] | None = None,
    show: bool = True,
    **options: Any,
) -> Played:
    """Play ``paths`` with ``options`` (no -d unless given), the ``actions`` at their times."""
    options.setdefault("delay", 0.0)
    vt.t, vt.actions = START, []  # each play from the start of virtual time
    node = node or FakeNode(vt.monotonic)
    readers: list[BagReader] = [open_bag(p) for p in paths]
    player = Player(node, readers, PlayOptions(**options))  # type: ignore[arg-type]
    shown: list[tuple[float, Status]] = []
    said: list[str] = []

    def record(status: Status) -> None:
        shown.append((vt.t - START, Status(**vars(status))))

    async def main() -> int:
        stop = asyncio.Event()
        for when, action in actions:
            vt.at(when, lambda a=action: a(player, node, stop))  # type: ignore[misc]
        task = None
        if during is not None:
            task = asyncio.get_running_loop().create_task(during(player, node, stop))
        count = await player.run(stop, record if show else None, said.append)
        if task is not None:
            await task
        return count

    try:
        count = asyncio.run(main())
    finally:
        for reader in readers:
            reader.close()
    return Played(node, player, count, vt.t - START, shown, said)


def pause(player: Player, node: FakeNode, stop: asyncio.Event) -> None:
    player.set_paused(True)


def resume(player: Player, node: FakeNode, stop: asyncio.Event) -> None:
    player.set_paused(False)


def step(player: Player, node: FakeNode, stop: asyncio.Event) -> None:
    player.step()


def halt(player: Player, node: FakeNode, stop: asyncio.Event) -> None:
    stop.set()


def stamp(bag_seconds: float) -> Callable[[Player, FakeNode, asyncio.Event], None]:
    """A message on the rate-control topic stamped ``bag_seconds`` after T0."""

    def send(player: Player, node: FakeNode, stop: asyncio.Event) -> None:
        conn = type("Conn", (), {"header": {"message_definition": STAMPED_DEF}})()
        t = T0 + round(bag_seconds * NS)
        node.subscribed["/ctl"]([struct.pack("<III", 0, t // NS, t % NS)], conn, 0.0)

    return send


def approx(values: list[float]) -> Any:
    return pytest.approx(values, abs=1e-9)


# what is advertised and sent -------------------------------------------------------------


def test_each_topic_gets_one_publisher_as_recorded(vt: VirtualTime, tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", [("/chatter", 0, "a"), ("/tf", 0.1, "b")])
    other = write_bag(tmp_path / "b.bag", [("/tf", 0.2, "c"), ("/chatter", 0.3, "d")])
    played = play(vt, [bag, other], immediate=True, prefix="/replay", queue_size=7)
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


def test_a_latched_connection_makes_its_topic_latched(vt: VirtualTime, tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", [("/chatter", 0, "a")])
    with open_writer(tmp_path / "b.bag") as writer:
        conn = writer.add_connection(
            "/chatter", "std_msgs/String", STRING_MD5, "string data\n", callerid="/l", latching=True
        )
        writer.write(conn, T0 + 1, string("b"))
    for order in ([bag, tmp_path / "b.bag"], [tmp_path / "b.bag", bag]):
        assert play(vt, order, immediate=True).node.publishers["/chatter"].latch


def test_start_and_duration_choose_the_messages_and_send_the_latched_before(
    vt: VirtualTime, tmp_path: Path
) -> None:
    """-s: what a late subscriber would still get (the last latched message) goes first."""
    messages = [("/latched", 0, "old"), ("/latched", 0.02, "last"), *TEN[1:]]
    bag = write_bag(tmp_path / "a.bag", messages)
    played = play(vt, [bag], immediate=True, start=0.035, duration=0.03)
    assert played.node.texts() == ["last", "m4", "m5", "m6"]
    assert played.node.sent[0].source == ("/latched", "/pub/latched")
    assert played.player.status.total == pytest.approx(0.03)
    whole = play(vt, [bag], immediate=True)
    assert whole.node.texts() == ["old", "m1", "last", *[f"m{i}" for i in range(2, 10)]]
    topics = play(vt, [bag], immediate=True, topics=["/chatter"], start=0.035)
    assert topics.node.texts() == ["m4", "m5", "m6", "m7", "m8", "m9"]
    assert set(topics.node.publishers) == {"/chatter"}
    assert play(vt, [bag], immediate=True, topics=["/latched"]).node.texts() == ["old", "last"]


def test_an_empty_bag_plays_nothing(vt: VirtualTime, tmp_path: Path) -> None:
    with open_writer(tmp_path / "empty.bag"):
        pass
    played = play(vt, [tmp_path / "empty.bag"])
    assert played.count == 0 and not played.node.sent
    assert (played.player.status.total, played.player.status.bag_time) == (0.0, 0)
    past = play(vt, [write_bag(tmp_path / "a.bag", TEN)], start=5.0)
    assert past.count == 0 and past.player.status.total == 0.0


# the pace ------------------------------------------------------------------------------


def test_messages_go_out_at_their_recorded_pace(vt: VirtualTime, tmp_path: Path) -> None:
    bag = write_bag(
        tmp_path / "a.bag",
        [
            ("/chatter", 0, "a"),
            ("/chatter", 0.013, "b"),
            ("/chatter", 1.5, "c"),
            ("/chatter", 1.52, "d"),
        ],
    )
    assert play(vt, [bag]).node.times() == approx([0.0, 0.013, 1.5, 1.52])


def test_a_rate_scales_the_pace(vt: VirtualTime, tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", [*TEN[:3], ("/chatter", 2.0, "z")])
    assert play(vt, [bag], rate=4.0).node.times() == approx([0.0, 0.0025, 0.005, 0.5])
    assert play(vt, [bag], rate=0.5).node.times() == approx([0.0, 0.02, 0.04, 4.0])


def test_play_starts_with_the_first_message_in_the_window(vt: VirtualTime, tmp_path: Path) -> None:
    """-s into a gap: the first message played goes at once, the rest at their pace from it."""
    bag = write_bag(
        tmp_path / "a.bag", [("/chatter", 0, "a"), ("/chatter", 3.0, "b"), ("/chatter", 3.2, "c")]
    )
    assert play(vt, [bag], start=0.1).node.times() == approx([0.0, 0.2])


def test_the_bag_time_playing_is_paced_by_the_rate(tmp_path: Path) -> None:
    """The status line's and /clock's bag time: from -s, at the rate, never past the next."""
    bag = write_bag(tmp_path / "a.bag", TEN)
    with open_bag(bag) as reader:
        player = Player(FakeNode(lambda: 0.0), [reader], PlayOptions(rate=2.0, start=0.01))  # type: ignore[arg-type]
        player._origin = 50.0
        assert player._bag_time(50.25, T0 + 10 * NS) == T0 + NS // 100 + NS // 2
        assert player._bag_time(50.25, T0 + NS // 10) == T0 + NS // 10


def test_a_long_gap_is_skipped_when_asked(vt: VirtualTime, tmp_path: Path) -> None:
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
    assert play(vt, [bag], skip_empty=2.0, rate=2.0).node.times() == approx([0, 0.5, 0.5, 0.7])
    # "more than": a gap of exactly --skip-empty is played
    assert play(vt, [bag], skip_empty=1.0).node.times()[:2] == approx([0, 1.0])


def test_the_clock_ticks_at_hz_with_the_bag_time(vt: VirtualTime, tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", [("/chatter", 0, "a"), ("/chatter", 0.2, "b")])
    played = play(vt, [bag], clock=True, hz=50, rate=2.0)
    clock = played.node.publishers["/clock"]
    assert clock.type == CLOCK and clock.queue_size == 1
    ticks = [s for s in played.node.sent if s.topic == "/clock"]
    assert [s.at for s in ticks] == approx([0.0, 0.02, 0.04, 0.06, 0.08, 0.1, 0.1])
    stamps = [a * NS + b for a, b in (struct.unpack("<II", s.data) for s in ticks)]
    # every 20 ms of play is 40 ms of bag at -r 2; the last, as play ends, is its end
    assert stamps == [T0 + k * 40_000_000 for k in range(6)] + [T0 + 2 * NS // 10]
    assert played.node.times() == approx([0.0, 0.1])


# pauses, steps, holds ---------------------------------------------------------------------


def test_paused_time_does_not_count(vt: VirtualTime, tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", [("/chatter", 0, "a"), ("/chatter", 0.4, "b")])
    played = play(vt, [bag], [(0.05, pause), (0.65, resume)])
    assert played.node.times() == approx([0.0, 1.0])  # b's 0.4 s, and the 0.6 s paused
    paused = [at for at, s in played.shown if s.state is State.PAUSED]
    assert len(paused) >= 5 and max(paused) < 0.65  # the status says so, ten times a second


def test_a_stop_while_paused_ends_play_at_once(vt: VirtualTime, tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", [("/chatter", 0, "a"), ("/chatter", 0.4, "b")])
    played = play(vt, [bag], [(0.1, pause), (0.25, halt)])
    assert played.node.texts() == ["a"] and played.ended == pytest.approx(0.25)
    assert played.shown[-1][1].state is State.DONE


def test_a_stop_while_waiting_ends_play_at_once(vt: VirtualTime, tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", [("/chatter", 0, "a"), ("/chatter", 60, "b")])
    played = play(vt, [bag], [(0.25, halt)])
    assert played.node.texts() == ["a"] and played.count == 1
    assert played.ended == pytest.approx(0.25)


def test_a_paused_start_waits_for_steps_and_keys(vt: VirtualTime, tmp_path: Path) -> None:
    """Steps send at once; what follows is timed from the last one sent."""
    bag = write_bag(
        tmp_path / "a.bag", [("/chatter", 0, "a"), ("/chatter", 2.0, "b"), ("/chatter", 2.1, "c")]
    )

    def two_steps(player: Player, node: FakeNode, stop: asyncio.Event) -> None:
        player.step()
        player.step()  # two presses of ``s`` before the player looks: two messages

    def toggle(player: Player, node: FakeNode, stop: asyncio.Event) -> None:
        player.toggle_pause()

    played = play(vt, [bag], [(0.15, two_steps), (0.35, toggle)], pause=True)
    assert played.node.times() == approx([0.15, 0.15, 0.45])
    assert played.player.steps == 0


def test_a_step_while_running_is_not_kept(vt: VirtualTime, tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", TEN[:1])
    with open_bag(bag) as reader:
        player = Player(FakeNode(vt.monotonic), [reader], PlayOptions())  # type: ignore[arg-type]
        player.step()
        assert player.steps == 0


def test_pause_topics_pause_before_their_messages(vt: VirtualTime, tmp_path: Path) -> None:
    bag = write_bag(
        tmp_path / "a.bag", [("/chatter", 0, "a"), ("/tf", 0.01, "t"), ("/chatter", 0.02, "b")]
    )
    played = play(vt, [bag], [(0.5, step), (0.7, resume)], pause_topics=["/tf"])
    assert played.node.texts() == ["a", "t", "b"]
    assert played.node.times() == approx([0.0, 0.7 + 0.01])  # /chatter: a, then b after t
    assert played.node.times("/tf") == approx([0.5])  # ``s`` sent it

    def toggle_topics(player: Player, node: FakeNode, stop: asyncio.Event) -> None:
        player.toggle_pause_topics()  # ``t``: they pause no more

    later = write_bag(
        tmp_path / "b.bag", [("/chatter", 0, "a"), ("/chatter", 0.005, "b"), ("/tf", 0.01, "t")]
    )
    free = play(vt, [later], [(0.001, toggle_topics)], pause_topics=["/tf"])
    assert free.node.times("/tf") == approx([0.01])


def test_the_keys_toggle(vt: VirtualTime, tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", TEN[:1])
    with open_bag(bag) as reader:
        player = Player(FakeNode(vt.monotonic), [reader], PlayOptions(pause_topics=["/tf"]))  # type: ignore[arg-type]
        player.toggle_pause()
        assert player.status.state is State.PAUSED
        player.toggle_pause()
        assert player.status.state is State.RUNNING
        player.toggle_pause_topics()
        player.toggle_pause_topics()
        assert player.pausing_on_topics


def test_the_pause_service_pauses_and_resumes(vt: VirtualTime, tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", [("/chatter", 0, "a"), ("/chatter", 0.5, "b")])
    answers: list[bytes] = []

    def ask(value: bytes) -> Callable[[Player, FakeNode, asyncio.Event], None]:
        def call(player: Player, node: FakeNode, stop: asyncio.Event) -> None:
            answers.append(node.services["~pause_playback"][1](value))

        return call

    played = play(vt, [bag], [(0.1, ask(b"\x01")), (0.2, ask(b"\x01")), (0.3, ask(b"\x00"))])
    assert played.node.times() == approx([0.0, 0.7])
    assert [a[:1] for a in answers] == [b"\x01", b"\x00", b"\x01"]  # changed, not, changed
    assert b"already paused" in answers[1]


def test_a_finished_play_stays_done_when_paused(vt: VirtualTime, tmp_path: Path) -> None:
    played = play(vt, [write_bag(tmp_path / "a.bag", TEN[:1])], immediate=True)
    played.player.set_paused(True)
    assert played.player.status.state is State.DONE


def test_the_rate_control_topic_holds_play_and_its_time_does_not_count(
    vt: VirtualTime, tmp_path: Path
) -> None:
    bag = write_bag(
        tmp_path / "a.bag", [("/chatter", 0, "a"), ("/chatter", 0.3, "b"), ("/chatter", 0.6, "c")]
    )
    played = play(
        vt, [bag], [(0.45, stamp(10.0))], rate_control_topic="/ctl", rate_control_max_delay=0.1
    )
    # b, 0.3 s ahead of the stamps, is held at once; its 0.3 s run from the stamp at 0.45
    assert played.node.times() == approx([0.0, 0.75, 1.05])
    held = [(at, s) for at, s in played.shown if s.state is State.DELAYED]
    assert len(held) >= 4 and all(at < 0.45 and s.delay == pytest.approx(0.3) for at, s in held)
    after = [s for at, s in played.shown if at > 0.45 and s.state is not State.DONE]
    assert after and all(s.state is State.RUNNING for s in after)


def test_a_stop_while_held_ends_play_at_once(vt: VirtualTime, tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", [("/chatter", 0, "a"), ("/chatter", 0.3, "b")])
    played = play(vt, [bag], [(0.45, halt)], rate_control_topic="/ctl", rate_control_max_delay=0.1)
    assert played.node.texts() == ["a"] and played.ended == pytest.approx(0.45)


# before and after play --------------------------------------------------------------------


def test_play_waits_for_the_delay_and_says_so(vt: VirtualTime, tmp_path: Path) -> None:
    played = play(vt, [write_bag(tmp_path / "a.bag", TEN[:1])], delay=0.25)
    assert played.node.times() == approx([0.25])
    assert played.said == ["Waiting 0.25 seconds after advertising topics... done.\n"]


def test_play_waits_for_subscribers_when_asked(vt: VirtualTime, tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", [("/chatter", 0, "a"), ("/tf", 0, "b")])

    def connect(topic: str) -> Callable[[Player, FakeNode, asyncio.Event], None]:
        def call(player: Player, node: FakeNode, stop: asyncio.Event) -> None:
            node.publishers[topic].subscriber_count = 1

        return call

    played = play(
        vt, [bag], [(0.1, connect("/chatter")), (0.32, connect("/tf"))], wait_for_subscribers=True
    )
    assert 0.32 <= played.node.sent[0].at <= 0.35 + 1e-9  # it looks every 50 ms
    assert played.said[:2] == ["Waiting for subscribers.\n", "Finished waiting for subscribers.\n"]


def test_play_waits_for_the_subscribers_the_master_listed(vt: VirtualTime, tmp_path: Path) -> None:
    """A roscpp subscriber connects some 250 ms after it is listed: its first message waits."""
    bag = write_bag(tmp_path / "a.bag", TEN[:1])
    node = FakeNode(vt.monotonic)
    node.listed["/chatter"] = ["/listener"]

    def connect(player: Player, node: FakeNode, stop: asyncio.Event) -> None:
        node.publishers["/chatter"].subscriber_count = 1

    played = play(vt, [bag], [(0.252, connect)], node=node)
    assert 0.252 <= played.node.sent[0].at <= 0.255 + 1e-9  # it looks every 5 ms
    dead = FakeNode(vt.monotonic)
    dead.listed["/chatter"] = ["/dead"]  # never connects: play waits CONNECT_GRACE only
    late = play(vt, [bag], node=dead)
    assert CONNECT_GRACE <= late.node.sent[0].at <= CONNECT_GRACE + 0.005 + 1e-9


def test_a_stop_before_play_sends_nothing(vt: VirtualTime, tmp_path: Path) -> None:
    """Ctrl-C during -d, or while play waits for subscribers, ends it at once."""
    bag = write_bag(tmp_path / "a.bag", [("/latched", 0, "map"), *TEN[1:]])
    delayed = play(vt, [bag], [(0.5123, halt)], delay=5.0, start=0.05)
    assert not delayed.node.sent and delayed.ended == pytest.approx(0.5123)
    waiting = play(vt, [bag], [(0.1234, halt)], wait_for_subscribers=True)
    assert not waiting.node.sent and waiting.ended == pytest.approx(0.1234)
    node = FakeNode(vt.monotonic)
    node.listed["/chatter"] = ["/dead"]
    listed = play(vt, [bag], [(0.1023, halt)], node=node)
    assert not listed.node.sent and listed.ended == pytest.approx(0.1023)


def test_a_loop_plays_again_until_stopped(vt: VirtualTime, tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", TEN[:3])
    played = play(vt, [bag], [(0.045, halt)], loop=True)
    assert played.node.texts() == ["m0", "m1", "m2"] * 2 + ["m0"]
    assert played.node.times() == approx([0.0, 0.01, 0.02, 0.02, 0.03, 0.04, 0.04])
    assert played.count == 7


def test_keep_alive_waits_for_the_stop(vt: VirtualTime, tmp_path: Path) -> None:
    stopped: list[bool] = []

    async def stop_once_done(player: Player, node: FakeNode, stop: asyncio.Event) -> None:
        while player.status.state is not State.DONE:
            await asyncio.sleep(0)
        for _ in range(10):  # the player goes on waiting
            await asyncio.sleep(0)
        stopped.append(True)
        stop.set()

    played = play(
        vt, [write_bag(tmp_path / "a.bag", TEN[:1])], during=stop_once_done, keep_alive=True
    )
    assert stopped and played.count == 1


# the status line --------------------------------------------------------------------------


def test_the_status_is_refreshed_ten_times_a_second(vt: VirtualTime, tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", [("/chatter", 0, "a"), ("/chatter", 0.5, "z")])
    played = play(vt, [bag])
    running = [(at, s) for at, s in played.shown if s.state is State.RUNNING]
    assert [at for at, _ in running] == approx([0.0, 0.1, 0.2, 0.3, 0.4])
    for at, s in running:
        assert s.bag_time == T0 + round(at * NS)  # the bag time playing then
        assert s.elapsed == pytest.approx((s.bag_time - T0) / NS)
    last = played.shown[-1][1]
    assert last.state is State.DONE and last.published == 2
    assert last.bag_time == T0 + NS // 2
    assert last.elapsed == last.total == pytest.approx(0.5)


def test_a_stopped_play_shows_the_last_message_sent(vt: VirtualTime, tmp_path: Path) -> None:
    """Stopped during an --immediate play: the last status has the last time sent."""
    bag = write_bag(tmp_path / "a.bag", [("/chatter", i * 0.001, f"m{i}") for i in range(3000)])

    async def stop_soon(player: Player, node: FakeNode, stop: asyncio.Event) -> None:
        while not node.sent:
            await asyncio.sleep(0)
        stop.set()

    played = play(vt, [bag], during=stop_soon, immediate=True)
    assert 0 < played.count < 3000
    last = played.shown[-1][1]
    assert last.state is State.DONE
    assert last.bag_time == T0 + round((played.count - 1) * 0.001 * NS)


def test_play_without_a_status_line(vt: VirtualTime, tmp_path: Path) -> None:
    """-q: no status shown, the messages as paced."""
    played = play(vt, [write_bag(tmp_path / "a.bag", TEN[:3])], show=False, clock=True)
    assert played.node.times() == approx([0.0, 0.01, 0.02])


def test_the_status_spans_the_messages_played(vt: VirtualTime, tmp_path: Path) -> None:
    bag = write_bag(tmp_path / "a.bag", [("/other", 0, "o"), *TEN[1:9], ("/other", 0.5, "o2")])

    def measured(**options: Any) -> Player:
        player = Player(FakeNode(vt.monotonic), readers, PlayOptions(**options))  # type: ignore[arg-type]
        player.measure()
        return player

    readers = [open_bag(bag)]
    try:
        whole = measured()
        assert (whole.shown_from, whole.shown_until, whole.status.total) == (T0, T0 + NS // 2, 0.5)
        some = measured(topics=["/chatter"], start=0.015)
        assert (some.shown_from, some.shown_until) == (T0 + 2 * NS // 100, T0 + 8 * NS // 100)
        assert some.status.total == pytest.approx(0.06)
        cut = measured(duration=0.055)
        assert (cut.shown_from, cut.shown_until) == (T0, T0 + 5 * NS // 100)
        none = measured(topics=["/chatter"], start=0.3)
        assert (none.shown_from, none.shown_until) == (none.from_ns, none.until_ns)
        exact = measured(duration=0.08)  # -u ending on a message keeps it
        assert exact.shown_until == T0 + 8 * NS // 100
        late = measured(start=0.015)  # -s alone: from the first message at or after it
        assert (late.shown_from, late.shown_until) == (T0 + 2 * NS // 100, T0 + NS // 2)
        assert measured(start=10.0).status.total == 0.0  # -s past the end: nothing plays
    finally:
        readers[0].close()


def test_the_status_spans_several_bags(vt: VirtualTime, tmp_path: Path) -> None:
    long = write_bag(tmp_path / "long.bag", [("/chatter", 0, "a"), ("/chatter", 0.5, "b")])
    short = write_bag(tmp_path / "short.bag", [("/chatter", 0.1, "c")])
    readers = [open_bag(long), open_bag(short)]
    try:
        player = Player(FakeNode(vt.monotonic), readers, PlayOptions(topics=["/chatter"]))  # type: ignore[arg-type]
        player.measure()
        assert (player.shown_from, player.shown_until) == (T0, T0 + NS // 2)
    finally:
        for reader in readers:
            reader.close()


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
        Player(FakeNode(lambda: 0.0), [reader], PlayOptions(**options))  # type: ignore[arg-type]
    assert str(refused.value) == why
    with open_bag(bag) as reader:  # --hz alone is not checked without --clock
        Player(FakeNode(lambda: 0.0), [reader], PlayOptions(hz=0.0))  # type: ignore[arg-type]
        Player(FakeNode(lambda: 0.0), [reader], PlayOptions(clock=True, hz=0.5))  # type: ignore[arg-type]
