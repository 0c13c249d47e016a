"""``subscriber.node_at``: one lookup of the publishers' names serves every report near it."""

from __future__ import annotations

import asyncio

import pytest

from rostools.node import subscriber


class _Owner:
    master_uri = "http://master:11311/"


def test_a_report_as_the_lookup_ends_takes_its_names(monkeypatch: pytest.MonkeyPatch) -> None:
    # The names were kept by those who waited for the lookup, on their next turn; a report
    # that came between the lookup's end and that turn found neither the names nor a lookup
    # under way, and looked every name up again (seen under load: two getSystemState calls).
    monkeypatch.setattr(subscriber, "_names", {})
    lookups: list[int] = []

    async def main() -> list[str | None]:
        loop = asyncio.get_running_loop()
        late: list[asyncio.Task[str | None]] = []

        def report_later() -> None:  # queued behind the lookup's own end callbacks
            late.append(loop.create_task(subscriber.node_at(_Owner(), "http://b:1/")))  # type: ignore[arg-type]

        async def names(owner: object) -> dict[str, str]:
            lookups.append(1)
            if len(lookups) == 1:
                loop.call_soon(loop.call_soon, report_later)
            await asyncio.sleep(0)
            return {"http://a:1/": "/a", "http://b:1/": "/b"}

        monkeypatch.setattr(subscriber, "publisher_names", names)
        first = await subscriber.node_at(_Owner(), "http://a:1/")  # type: ignore[arg-type]
        while not late:
            await asyncio.sleep(0)
        return [first, await late[0]]

    assert asyncio.run(main()) == ["/a", "/b"]
    assert len(lookups) == 1
