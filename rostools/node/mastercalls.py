"""The live node's typed master API: the async twin of ``rosgraph.masterapi.MasterProxy``.

Every call a node makes to the master, and to another node's slave API, goes through here:
``rosgraph.masterapi.call_error`` turns a failed exchange into our error and ``ros_value``
reads the ``[code, message, value]`` triple, so nothing else unpacks one.
"""

from __future__ import annotations

from typing import Any

from rostools.errors import RostoolsError
from rostools.node.rpc import CALL_TIMEOUT, call
from rostools.rosgraph.masterapi import MasterError, call_error, master_timeout, ros_value


async def peer_value(
    uri: str, caller_id: str, method: str, *args: Any, timeout: float | None = None
) -> Any:
    """The value of a node's slave API ``method``; ``MasterError`` for a failure code.

    The call has ``CALL_TIMEOUT`` unless ``timeout`` says otherwise. Transport errors stay
    as they are (``OSError``, ``TimeoutError``, ``Fault``): a caller that tells a user why a
    peer failed reads them with ``network.explain``.
    """
    limit = CALL_TIMEOUT if timeout is None else timeout
    return ros_value(await call(uri, method, (caller_id, *args), limit), method, "node")


class LiveMaster:
    """The master, as the node ``caller_id`` asks it from an event loop."""

    def __init__(self, uri: str, caller_id: str) -> None:
        self.uri = uri
        self.caller_id = caller_id

    async def call(self, method: str, *args: Any, timeout: float | None = None) -> Any:
        """The value of ``method``; our errors as every master client gives them."""
        answer = await self._answer(method, (self.caller_id, *args), timeout)
        return ros_value(answer, method, "master", args)

    async def _answer(self, method: str, params: tuple[Any, ...], timeout: float | None) -> Any:
        """The whole answer to ``method``; a failed exchange as our error."""
        limit = master_timeout() if timeout is None else timeout
        try:
            return await call(self.uri, method, params, limit)
        except Exception as err:
            error = call_error(err, self.uri, "master", method, limit)
            if error is None:
                raise
            raise error from err

    async def multicall(
        self, calls: list[tuple[str, tuple[Any, ...]]], timeout: float | None = None
    ) -> list[Any]:
        """Several calls in one ``system.multicall``: each one's value, or its error."""
        multi = [{"methodName": m, "params": [self.caller_id, *p]} for m, p in calls]
        answers = await self._answer("system.multicall", (multi,), timeout)
        if not isinstance(answers, list):
            raise RostoolsError(f"bad answer from the master at {self.uri} to system.multicall")
        results: list[Any] = []
        for (method, params), answer in zip(calls, answers, strict=False):
            if isinstance(answer, list) and len(answer) == 1:
                try:
                    results.append(ros_value(answer[0], method, "master", params))
                except Exception as err:  # noqa: BLE001 - given back as this entry's result
                    results.append(err)
            else:  # a fault struct
                text = answer.get("faultString", "") if isinstance(answer, dict) else answer
                results.append(MasterError(method, 0, str(text)))
        return results

    async def system_state(
        self, timeout: float | None = None
    ) -> tuple[list[Any], list[Any], list[Any]]:
        """Publishers, subscribers and services."""
        pubs, subs, srvs = await self.call("getSystemState", timeout=timeout)
        return pubs, subs, srvs

    async def published_topics(self, timeout: float | None = None) -> dict[str, str]:
        """Topic -> type, for every topic with a publisher (a tenth of ``getSystemState``)."""
        answer = await self.call("getPublishedTopics", "", timeout=timeout)
        return {str(t[0]): str(t[1]) for t in answer if isinstance(t, list) and len(t) == 2}

    async def topic_types(self, timeout: float | None = None) -> dict[str, str]:
        """Topic -> type, for every topic the master has seen typed."""
        return dict(await self.call("getTopicTypes", timeout=timeout))

    async def lookup_node(self, name: str, timeout: float | None = None) -> str:
        """A node's XML-RPC URI; ``NotFoundError`` for an unknown node."""
        return str(await self.call("lookupNode", name, timeout=timeout))

    async def lookup_service(self, name: str) -> str:
        """A service's rosrpc URI; ``NotFoundError`` for an unknown service."""
        return str(await self.call("lookupService", name))

    async def get_param(self, key: str) -> Any:
        """A parameter's value; ``NotFoundError`` when unset."""
        return await self.call("getParam", key)

    async def has_param(self, key: str) -> bool:
        """Whether a parameter is set."""
        return bool(await self.call("hasParam", key))

    async def set_param(self, key: str, value: Any) -> None:
        """Set a parameter (a dict sets a tree)."""
        await self.call("setParam", key, value)

    async def delete_param(self, key: str) -> None:
        """Delete a parameter; ``NotFoundError`` when unset."""
        await self.call("deleteParam", key)

    async def unregister_subscriber(self, topic: str, api: str) -> None:
        """Withdraw a subscription."""
        await self.call("unregisterSubscriber", topic, api)


def uris_of(value: Any) -> list[str]:
    """The URIs of a register call's answer (a peer's junk entries left out)."""
    return [u for u in value if isinstance(u, str)] if isinstance(value, list) else []
