"""``node/registration.Registrar``: a registration the master is slow to take is tried again."""

from __future__ import annotations

import asyncio
from collections.abc import Callable
from typing import Any

import pytest

from rostools.errors import TimeoutExpired, UnreachableError
from rostools.node import registration
from rostools.node.notice import Notice
from rostools.rosgraph.masterapi import MasterError


class _Owner:
    """What a registrar asks of its node: where the master is, and where notices go."""

    master_uri = "http://master:11311/"

    def __init__(self) -> None:
        self.notices: list[Notice] = []

    def notify(self, notice: Notice) -> None:
        self.notices.append(notice)


def _slow(answers: list[Any], limits: list[float]) -> Callable[[float], Any]:
    """An attempt that gives (or raises) ``answers`` in turn and notes each try's limit."""

    async def attempt(limit: float) -> Any:
        limits.append(limit)
        answer = answers.pop(0)
        if isinstance(answer, Exception):
            raise answer
        return answer

    return attempt


@pytest.fixture(autouse=True)
def _quick(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(registration, "RETRY_FIRST", 0.001)
    monkeypatch.setattr(registration, "RETRY_MAX", 0.004)
    monkeypatch.setenv("ROSTOOLS_MASTER_TIMEOUT", "3")


async def _settle(registrar: registration.Registrar) -> None:
    while registrar.pending:
        await asyncio.gather(*registrar.pending.values(), return_exceptions=True)


def test_a_registration_that_times_out_is_tried_again_until_taken() -> None:
    owner, taken, limits = _Owner(), [], []
    late = TimeoutExpired("the master at http://master:11311/ did not answer registerX within 3 s")

    async def main() -> registration.Registrar:
        registrar = registration.Registrar(owner)  # type: ignore[arg-type]
        attempt = _slow([late, late, UnreachableError("gone"), ["uri"]], limits)
        await registrar.register("subscription /t", attempt, taken.append, lambda: True)
        assert registrar.pending  # the command goes on; the registration waits
        await _settle(registrar)
        return registrar

    registrar = asyncio.run(main())
    assert taken == [["uri"]]
    assert registrar.confirmed
    # each try may take twice as long as the one before, up to LIMIT_MAX
    assert limits == [3.0, 6.0, 12.0, 24.0]
    assert [n.event for n in owner.notices] == ["register_retry", "registered"]
    assert owner.notices[0].message == (
        "the master at http://master:11311/ did not answer registerX within 3 s; "
        "registering subscription /t again until it answers"
    )
    assert owner.notices[1].message.startswith(
        "the master at http://master:11311/ has taken 1 registration(s) it was slow to answer"
    )


def test_one_line_for_an_episode_however_many_registrations_wait() -> None:
    owner, taken = _Owner(), []
    late = TimeoutExpired("late")

    async def main() -> None:
        registrar = registration.Registrar(owner)  # type: ignore[arg-type]
        for i in range(50):
            attempt = _slow([late, i], [])
            await registrar.register(f"subscription /t{i}", attempt, taken.append, lambda: True)
        await _settle(registrar)

    asyncio.run(main())
    assert sorted(taken) == list(range(50))
    assert [n.event for n in owner.notices] == ["register_retry", "registered"]
    assert "has taken 50 registration(s)" in owner.notices[1].message


def test_a_closed_endpoint_is_not_registered_again() -> None:
    owner, taken, limits = _Owner(), [], []
    current = [True]

    async def main() -> None:
        registrar = registration.Registrar(owner)  # type: ignore[arg-type]
        attempt = _slow([TimeoutExpired("late"), ["uri"]], limits)
        await registrar.register("subscription /t", attempt, taken.append, lambda: current[0])
        current[0] = False  # unsubscribed before the next try
        await _settle(registrar)

    asyncio.run(main())
    assert taken == []
    assert len(limits) == 1
    assert [n.event for n in owner.notices] == ["register_retry"]  # nothing was taken


def test_a_refusal_is_raised_at_once_and_said_when_it_comes_later() -> None:
    owner = _Owner()

    async def main() -> None:
        registrar = registration.Registrar(owner)  # type: ignore[arg-type]
        with pytest.raises(MasterError):
            refused = _slow([MasterError("registerSubscriber", -1, "bad type")], [])
            await registrar.register("subscription /a", refused, print, lambda: True)
        attempt = _slow([TimeoutExpired("late"), MasterError("registerSubscriber", -1, "no")], [])
        await registrar.register("subscription /b", attempt, print, lambda: True)
        await _settle(registrar)

    asyncio.run(main())
    assert [n.event for n in owner.notices] == ["register_retry", "register_refused"]
    assert owner.notices[1].message == "the master refused subscription /b: no"


def test_close_stops_every_try() -> None:
    owner, limits = _Owner(), []

    async def main() -> None:
        registrar = registration.Registrar(owner)  # type: ignore[arg-type]
        attempt = _slow([TimeoutExpired("late")] * 1000, limits)
        await registrar.register("subscription /t", attempt, print, lambda: True)
        task = registrar.pending["subscription /t"]
        registrar.close()
        await asyncio.gather(task, return_exceptions=True)
        assert task.cancelled()
        assert not registrar.pending

    asyncio.run(main())
    assert len(limits) == 1
