"""Registrations the master is too slow to take, tried again until it takes them.

A master that answers ``registerSubscriber`` after our ``ROSTOOLS_MASTER_TIMEOUT`` (a busy
rosmaster with a thousand topics, a machine under load) must not cost a topic. rospy and
roscpp wait for the master however long it takes. A node of ours keeps the endpoint, says so
in one line, and registers it again in the background until the master answers: the waits
between tries and each try's limit both double, up to ``RETRY_MAX`` and ``LIMIT_MAX``. What
bounds the wait is the command's own ``--timeout``, never this.

Registrations made in one turn of the event loop go to the master in one ``system.multicall``
(a recorder that follows a thousand new topics makes ten calls, not a thousand).
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from rostools.errors import RostoolsError, TimeoutExpired, UnreachableError
from rostools.node.notice import Notice
from rostools.rosgraph.masterapi import master_timeout, no_answer

if TYPE_CHECKING:
    from rostools.node.endpoint import Owner

log = logging.getLogger(__name__)

#: The first wait before a registration is tried again, and the longest (s).
RETRY_FIRST, RETRY_MAX = 0.5, 5.0
#: Each try may take twice as long as the one before, up to this (s).
LIMIT_MAX = 30.0
#: The errors that mean "not yet": the master did not answer in time, or is away for now.
NOT_YET = (TimeoutExpired, UnreachableError)


def longer(limit: float) -> float:
    """The limit of the next try of a call that took longer than ``limit``."""
    return min(limit * 2, max(LIMIT_MAX, limit))


@dataclass
class Registration:
    """One endpoint to register with the master, and what to do with the answer.

    ``current`` says whether the endpoint is still ours: one closed meanwhile is not
    registered again.
    """

    name: str  # for people: "subscription /chatter"
    method: str
    params: tuple[Any, ...]
    take: Callable[[Any], None]
    current: Callable[[], bool]
    #: Not the user's own (a node's logger services): its waits are counted, never said.
    quiet: bool = False


@dataclass
class _Episode:
    """A time the master was slow: since when, registrations tried again, and taken."""

    since: float = field(default_factory=time.monotonic)
    retried: int = 0
    taken: int = 0
    #: Whether its first line was said: only a registration that is not quiet says it.
    said: bool = False


class Registrar:
    """A node's registrations: made at once, or tried again in the background."""

    def __init__(self, owner: Owner) -> None:
        self.owner = owner
        #: The registrations being tried again, by name.
        self.pending: dict[str, asyncio.Task[None]] = {}
        #: Whether the master has taken any registration of ours.
        self.confirmed = False
        self._episode: _Episode | None = None
        #: Registrations asked in this turn of the loop, and the calls under way.
        self._batch: list[tuple[Registration, asyncio.Future[Any]]] = []
        self._sending: set[asyncio.Task[None]] = set()

    async def register(self, reg: Registration) -> None:
        """Register, and give the master's answer to ``reg.take``.

        If the master does not answer in time, or cannot be reached, the registration is
        tried again in the background while ``reg.current()`` holds. A refusal (a failure
        code) is raised, as before.
        """
        self.forget(reg.name)
        try:
            value = await self._batched(reg)
        except NOT_YET as err:
            self._start_episode(err, reg)
            self.pending[reg.name] = asyncio.get_running_loop().create_task(self._again(reg))
            return
        self.confirmed = True
        reg.take(value)

    def _batched(self, reg: Registration) -> asyncio.Future[Any]:
        """The answer to ``reg``, asked with the others of this turn of the loop."""
        loop = asyncio.get_running_loop()
        answer: asyncio.Future[Any] = loop.create_future()
        self._batch.append((reg, answer))
        if len(self._batch) == 1:
            loop.call_soon(self._send_batch)
        return answer

    def _send_batch(self) -> None:
        batch, self._batch = self._batch, []
        task = asyncio.get_running_loop().create_task(self._send(batch))
        self._sending.add(task)
        task.add_done_callback(self._sending.discard)

    async def _send(self, batch: list[tuple[Registration, asyncio.Future[Any]]]) -> None:
        """One call, or one ``system.multicall``; each registration gets its own answer."""
        master, limit = self.owner.master, master_timeout()
        results: list[Any]
        try:
            if len(batch) == 1:
                reg = batch[0][0]
                results = [await master.call(reg.method, *reg.params, timeout=limit)]
            else:
                calls = [(reg.method, reg.params) for reg, _ in batch]
                results = await master.multicall(calls, timeout=limit)
        except TimeoutExpired:  # each registration is said to be late in its own words
            uri = self.owner.master_uri
            results = [no_answer(uri, "master", reg.method, limit) for reg, _ in batch]
        except Exception as err:  # noqa: BLE001 - the whole call failed: each registration did
            results = [err] * len(batch)
        if len(results) != len(batch):
            wrong = f"bad answer from the master at {self.owner.master_uri} to system.multicall"
            results = [RostoolsError(wrong)] * len(batch)
        for (_, answer), result in zip(batch, results, strict=True):
            if answer.done():
                continue
            if isinstance(result, BaseException):
                answer.set_exception(result)
            else:
                answer.set_result(result)

    def forget(self, name: str) -> None:
        """Stop trying ``name`` again (it was registered another way, or closed)."""
        task = self.pending.pop(name, None)
        if task is not None:
            task.cancel()
            self._end_episode()

    def close(self) -> None:
        """Stop every try (the node is closing)."""
        for task in self.pending.values():
            task.cancel()
        self.pending.clear()

    async def _again(self, reg: Registration) -> None:
        wait, limit = RETRY_FIRST, master_timeout()
        try:
            while reg.current():
                await asyncio.sleep(wait)
                wait, limit = min(wait * 2, RETRY_MAX), longer(limit)
                if not reg.current():
                    break
                try:
                    value = await self.owner.master.call(reg.method, *reg.params, timeout=limit)
                except NOT_YET as err:
                    log.debug("registering %s again: %s", reg.name, err)
                    continue
                except RostoolsError as err:  # the master answered: it refuses
                    self.owner.notify(
                        Notice("register_refused", f"the master refused {reg.name}: {err}")
                    )
                    break
                self.confirmed = True
                if reg.current():
                    reg.take(value)
                    if self._episode is not None and not reg.quiet:
                        self._episode.taken += 1
                break
        finally:
            if self.pending.get(reg.name) is asyncio.current_task():
                del self.pending[reg.name]
                self._end_episode()

    def _start_episode(self, err: RostoolsError, reg: Registration) -> None:
        """One line when the first registration of an episode that is not quiet has to wait."""
        if self._episode is None:
            self._episode = _Episode()
        if reg.quiet:
            return
        self._episode.retried += 1
        if self._episode.said:
            return
        self._episode.said = True
        self.owner.notify(
            Notice(
                "register_retry",
                f"{err}; registering {reg.name} again until it answers",
                {"uri": self.owner.master_uri, "name": reg.name},
            )
        )

    def _end_episode(self) -> None:
        """One line when the last registration of an episode is through.

        Nothing when none went through: those left were closed, or refused (said already).
        """
        if self.pending or self._episode is None:
            return
        episode, self._episode = self._episode, None
        if not episode.taken:
            return
        took = time.monotonic() - episode.since
        of = "" if episode.taken == episode.retried else f" of {episode.retried}"
        self.owner.notify(
            Notice(
                "registered",
                f"the master at {self.owner.master_uri} has taken {episode.taken}{of} "
                f"registration(s) it was slow to answer, after {took:.1f} s",
                {"uri": self.owner.master_uri, "registrations": episode.taken, "seconds": took},
            )
        )
