"""The blocking API is the async one's twin: the same names, signatures and docstrings.

``Node`` runs ``AsyncNode`` on a background loop, and ``Publisher`` wraps ``AsyncPublisher``
(``_api/blocking.py``). A method added to one and not the other, a parameter that drifts, or
a docstring that tells one story for one and another for the other fails here.
"""

from __future__ import annotations

import ast
import inspect
from typing import Any

import pytest

from rostools._api.asyncnode import AsyncNode, AsyncPublisher
from rostools._api.blocking import Node, Publisher

TWINS = [(Node, AsyncNode), (Publisher, AsyncPublisher)]

#: What only the async twin has, and why the blocking one does without.
ASYNC_ONLY = {
    (AsyncNode, "start"): "a blocking Node starts in its constructor",
    (AsyncNode, "listen_raw"): "raw frames are handed over on the loop, where nothing may block",
}


def public(kind: type) -> set[str]:
    """A class's public methods and properties."""
    return {name for name in dir(kind) if not name.startswith("_")}


def attributes(kind: type) -> set[str]:
    """The public attributes ``__init__`` sets on an instance (``self.closed = False``)."""
    tree = ast.parse(inspect.getsource(kind.__init__).strip().replace("\n    ", "\n"))
    return {
        node.attr
        for node in ast.walk(tree)
        if isinstance(node, ast.Attribute)
        and isinstance(node.ctx, ast.Store)
        and isinstance(node.value, ast.Name)
        and node.value.id == "self"
        and not node.attr.startswith("_")
    }


def plain(text: str) -> str:
    """A signature with the twins' own names made one: ``AsyncPublisher`` is ``Publisher``."""
    text = text.replace("AsyncPublisher", "Publisher").replace("AsyncSubscription", "Subscription")
    return text.replace(" | Awaitable[Values]", "")  # an async handler may be a coroutine


def members(kind: type, name: str) -> Any:
    found = inspect.getattr_static(kind, name)
    return found.fget if isinstance(found, property) else found


@pytest.mark.parametrize(("blocking", "async_"), TWINS, ids=lambda k: k.__name__)
def test_the_same_names(blocking: type, async_: type) -> None:
    only_async = {n for n in public(async_) - public(blocking) if (async_, n) not in ASYNC_ONLY}
    only_blocking = public(blocking) - public(async_) - attributes(async_)
    assert not only_async, f"{blocking.__name__} lacks {sorted(only_async)}"
    assert not only_blocking, f"{async_.__name__} lacks {sorted(only_blocking)}"


PAIRS = [
    (blocking, async_, name)
    for blocking, async_ in TWINS
    for name in sorted(public(blocking) & public(async_))
]


@pytest.mark.parametrize(
    ("blocking", "async_", "name"), PAIRS, ids=[f"{b.__name__}.{n}" for b, _, n in PAIRS]
)
def test_the_same_signature_and_docstring(blocking: type, async_: type, name: str) -> None:
    mine, theirs = members(blocking, name), members(async_, name)
    assert plain(str(inspect.signature(mine))) == plain(str(inspect.signature(theirs)))
    assert inspect.getdoc(mine) == inspect.getdoc(theirs)
    assert inspect.iscoroutinefunction(mine) is False  # the blocking twin never needs await


def test_the_constructors_take_the_same_arguments() -> None:
    assert inspect.signature(Node.__init__) == inspect.signature(AsyncNode.__init__)


def test_drift_is_seen() -> None:
    """A renamed parameter or a docstring of its own would be told apart."""

    class Drifted:
        def resolve(self, other: str) -> str:
            """Something else."""
            return other

    assert plain(str(inspect.signature(Drifted.resolve))) != plain(
        str(inspect.signature(AsyncNode.resolve))
    )
    assert inspect.getdoc(Drifted.resolve) != inspect.getdoc(AsyncNode.resolve)
    assert "closed" in attributes(AsyncNode)
