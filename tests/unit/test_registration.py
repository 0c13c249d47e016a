"""``node/registration.Registrar``: a registration the master is slow to take is tried again."""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Any

import pytest

from rostools.errors import TimeoutExpired, UnreachableError
from rostools.node import registration
from rostools.node.notice import Notice
from rostools.node.registration import Registrar, Registration
from rostools.rosgraph.masterapi import MasterError

LATE = TimeoutExpired("the master at http://master:11311/ did not answer registerX within 3 s")


class _Master:
    """Answers each call with the next of ``answers`` (raised if an exception); notes the calls.

    ``answers`` may be a function of the call's first argument, for a multicall's entries.
    """

    def __init__(self, answers: list[Any] | Callable[[Any], Any]) -> None:
        self.answers = answers
        self.limits: list[float | None] = []
        self.multicalls: list[int] = []

    def _next(self, name: Any) -> Any:
        if callable(self.answers):
            return self.answers(name)
        return self.answers.pop(0)

    async def call(self, method: str, *params: Any, timeout: float | None = None) -> Any:
        self.limits.append(timeout)
        answer = self._next(params[0])
        if isinstance(answer, Exception):
            raise answer
        return answer

    async def multicall(
        self, calls: list[tuple[str, tuple[Any, ...]]], timeout: float | None = None
    ) -> list[Any]:
        self.limits.append(timeout)
        self.multicalls.append(len(calls))
        if not callable(self.answers) and isinstance(self.answers[0], NotImplementedError):
            raise self.answers.pop(0).args[0]  # the whole multicall fails
        return [self._next(params[0]) for _, params in calls]


class _Owner:
    """What a registrar asks of its node: the master, and where notices go."""

    master_uri = "http://master:11311/"

    def __init__(self, master: _Master) -> None:
        self.master = master
        self.notices: list[Notice] = []

    def notify(self, notice: Notice) -> None:
        self.notices.append(notice)


@pytest.fixture(autouse=True)
def _quick(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(registration, "RETRY_FIRST", 0.001)
    monkeypatch.setattr(registration, "RETRY_MAX", 0.004)
    monkeypatch.setenv("ROSTOOLS_MASTER_TIMEOUT", "3")


def _reg(name: str, taken: list[Any], current: Callable[[], bool] = lambda: True) -> Registration:
    return Registration(
        name, "registerSubscriber", (name, "*", "http://me/"), taken.append, current
    )


async def _settle(registrar: Registrar) -> None:
    while registrar.pending:
        await asyncio.gather(*registrar.pending.values(), return_exceptions=True)


def test_a_registration_that_times_out_is_tried_again_until_taken() -> None:
    master, taken = _Master([LATE, LATE, UnreachableError("gone"), ["uri"]]), []
    owner = _Owner(master)

    async def main() -> Registrar:
        registrar = Registrar(owner)  # type: ignore[arg-type]
        await registrar.register(_reg("/t", taken))
        assert registrar.pending  # the command goes on; the registration waits
        await _settle(registrar)
        return registrar

    registrar = asyncio.run(main())
    assert taken == [["uri"]]
    assert registrar.confirmed
    # each try may take twice as long as the one before, up to LIMIT_MAX
    assert master.limits == [3.0, 6.0, 12.0, 24.0]
    assert [n.event for n in owner.notices] == ["register_retry", "registered"]
    assert owner.notices[0].message == (
        "the master at http://master:11311/ did not answer registerSubscriber within 3 s; "
        "registering /t again until it answers"
    )
    assert owner.notices[1].message.startswith(
        "the master at http://master:11311/ has taken 1 registration(s) it was slow to answer"
    )


def test_registrations_of_one_turn_go_in_one_multicall() -> None:
    # A recorder that follows a thousand new topics made a thousand calls to a busy master.
    master, taken = _Master(lambda name: [f"uri of {name}"]), []

    async def main() -> None:
        registrar = Registrar(_Owner(master))  # type: ignore[arg-type]
        await asyncio.gather(*(registrar.register(_reg(f"/t{i}", taken)) for i in range(50)))
        await registrar.register(_reg("/alone", taken))

    asyncio.run(main())
    assert master.multicalls == [50]
    assert len(master.limits) == 2  # the multicall, then one plain call
    assert sorted(taken) == sorted([[f"uri of /t{i}"] for i in range(50)] + [["uri of /alone"]])


def test_a_multicall_that_times_out_leaves_each_registration_to_try_again() -> None:
    master, taken = _Master([NotImplementedError(LATE), ["a"], ["b"]]), []
    owner = _Owner(master)

    async def main() -> None:
        registrar = Registrar(owner)  # type: ignore[arg-type]
        await asyncio.gather(*(registrar.register(_reg(n, taken)) for n in ("/a", "/b")))
        await _settle(registrar)

    asyncio.run(main())
    assert sorted(taken) == [["a"], ["b"]]
    assert [n.event for n in owner.notices] == ["register_retry", "registered"]
    assert "has taken 2 registration(s)" in owner.notices[1].message


def test_one_line_for_an_episode_however_many_registrations_wait() -> None:
    tries: dict[str, int] = {}

    def late_once(name: str) -> Any:
        tries[name] = tries.get(name, 0) + 1
        return LATE if tries[name] == 1 else name

    master, taken = _Master(late_once), []
    owner = _Owner(master)

    async def main() -> None:
        registrar = Registrar(owner)  # type: ignore[arg-type]
        for i in range(50):  # one at a time: no batch
            await registrar.register(_reg(f"/t{i}", taken))
        await _settle(registrar)

    asyncio.run(main())
    assert sorted(taken) == sorted(f"/t{i}" for i in range(50))
    assert [n.event for n in owner.notices] == ["register_retry", "registered"]
    assert "has taken 50 registration(s)" in owner.notices[1].message


def test_a_quiet_registration_waits_unsaid_and_leaves_the_line_to_the_users_own() -> None:
    # the defect: a node's logger services, registered in the background as it starts, were
    # first to wait on a slow master, so `bag record` said "registering service
    # /rostools_record_.../set_logger_level again" and never named the topic that waited
    tries: dict[str, int] = {}

    def late_once(name: str) -> Any:
        tries[name] = tries.get(name, 0) + 1
        return LATE if tries[name] == 1 else name

    master, taken = _Master(late_once), []
    owner = _Owner(master)
    quiet = Registration("service /n/get_loggers", "registerService", ("/n/get_loggers",),
                         taken.append, lambda: True, quiet=True)  # fmt: skip

    async def main() -> list[Notice]:
        registrar = Registrar(owner)  # type: ignore[arg-type]
        await registrar.register(quiet)
        await _settle(registrar)
        alone = list(owner.notices)
        await registrar.register(Registration(**{**vars(quiet), "name": "service /n/x"}))
        await registrar.register(_reg("/chatter", taken))
        await _settle(registrar)
        return alone

    alone = asyncio.run(main())
    assert alone == []  # a quiet registration alone says nothing, and is taken
    assert "/n/get_loggers" in taken
    assert [n.event for n in owner.notices] == ["register_retry", "registered"]
    assert "registering /chatter again" in owner.notices[0].message
    assert "has taken 1 registration(s)" in owner.notices[1].message


def test_a_closed_endpoint_is_not_registered_again() -> None:
    master, taken = _Master([LATE, ["uri"]]), []
    owner = _Owner(master)
    current = [True]

    async def main() -> None:
        registrar = Registrar(owner)  # type: ignore[arg-type]
        await registrar.register(_reg("/t", taken, lambda: current[0]))
        current[0] = False  # unsubscribed before the next try
        await _settle(registrar)

    asyncio.run(main())
    assert taken == []
    assert len(master.limits) == 1
    assert [n.event for n in owner.notices] == ["register_retry"]  # nothing was taken


def test_a_refusal_is_raised_at_once_and_said_when_it_comes_later() -> None:
    refused = MasterError("registerSubscriber", -1, "no")
    master = _Master([MasterError("registerSubscriber", -1, "bad type"), LATE, refused])
    owner = _Owner(master)

    async def main() -> None:
        registrar = Registrar(owner)  # type: ignore[arg-type]
        with pytest.raises(MasterError):
            await registrar.register(_reg("/a", []))
        await registrar.register(_reg("/b", []))
        await _settle(registrar)

    asyncio.run(main())
    assert [n.event for n in owner.notices] == ["register_retry", "register_refused"]
    assert owner.notices[1].message == "the master refused /b: no"


def test_close_stops_every_try() -> None:
    master = _Master([LATE] * 1000)

    async def main() -> None:
        registrar = Registrar(_Owner(master))  # type: ignore[arg-type]
        await registrar.register(_reg("/t", []))
        task = registrar.pending["/t"]
        registrar.close()
        await asyncio.gather(task, return_exceptions=True)
        assert task.cancelled()
        assert not registrar.pending

    asyncio.run(main())
    assert len(master.limits) == 1


def test_a_multicall_answer_short_of_entries_fails_every_registration() -> None:
    # Each registration awaited an answer of its own: one left without would wait forever.
    class _Short(_Master):
        async def multicall(
            self, calls: list[tuple[str, tuple[Any, ...]]], timeout: float | None = None
        ) -> list[Any]:
            return [["uri"]]

    async def main() -> list[Any]:
        registrar = Registrar(_Owner(_Short([])))  # type: ignore[arg-type]
        regs = (registrar.register(_reg(n, [])) for n in ("/a", "/b"))
        return await asyncio.wait_for(asyncio.gather(*regs, return_exceptions=True), 5)

    outcomes = asyncio.run(main())
    assert [str(o) for o in outcomes] == [
        "bad answer from the master at http://master:11311/ to system.multicall"
    ] * 2
