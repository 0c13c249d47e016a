"""The parameter tree, with rosmaster's semantics (https://wiki.ros.org/ROS/Parameter%20Server).

Setting a dict replaces the subtree; setting below a non-dict turns it into a dict; deleting
a namespace deletes the subtree. Subscriptions are keyed by the canonical key with a trailing
slash, and every change yields the ``paramUpdate`` calls to make.
"""

from __future__ import annotations

from typing import Any

from rostools.names import GLOBAL_NS, SEP, canonicalize, is_global, is_private
from rostools.wire.rosapi import Failure

#: How deep the tree may nest, key segments and value levels together. Encoding and walking
#: it recurse; rosmaster stores a parameter 100,000 levels deep and then fails every
#: ``getParam /`` with a RecursionError. Real configurations nest about ten levels.
MAX_DEPTH = 100

#: (caller_id, caller_api) pairs subscribed to one key.
Subscribers = list[tuple[str, str]]
#: A paramUpdate to send: (caller_id, caller_api, key, value); ``{}`` means deleted.
Update = tuple[str, str, str, Any]


def _parts(key: str) -> list[str]:
    return [p for p in key.split(SEP) if p]


def subscription_key(key: str) -> str:
    """How subscriptions are stored: canonical, with a trailing slash."""
    return key if key == SEP else canonicalize(key) + SEP


class ParamTree:
    """A nested dict of parameters; it computes the updates its subscribers must get."""

    def __init__(self, subscribers: dict[str, Subscribers] | None = None) -> None:
        self.root: dict[str, Any] = {}
        #: subscription key -> subscribers; owned by the master's registry.
        self.subscribers: dict[str, Subscribers] = subscribers if subscribers is not None else {}

    def get(self, key: str) -> Any:
        """The value at ``key`` (a dict for a namespace); KeyError when unset."""
        value: Any = self.root
        for part in _parts(key):
            if not isinstance(value, dict):
                raise KeyError(key)
            value = value[part]
        return value

    def has(self, key: str) -> bool:
        """Whether ``key`` is set."""
        try:
            self.get(key)
        except KeyError:
            return False
        return True

    def set(self, key: str, value: Any, caller_id: str | None = None) -> list[Update]:
        """Set ``key``; the paramUpdates to send (the setter itself is not told).

        ValueError when the tree would nest deeper than ``MAX_DEPTH``.
        """
        if len(_parts(key)) + nesting(value) > MAX_DEPTH:
            raise ValueError(f"parameter [{key}] would nest deeper than {MAX_DEPTH} levels")
        if key == GLOBAL_NS:
            if not isinstance(value, dict):
                raise TypeError("cannot set root of parameter tree to non-dictionary")
            self.root = value
        else:
            *path, leaf = _parts(key)
            node = self.root
            for part in path:
                child = node.get(part)
                if not isinstance(child, dict):
                    child = node[part] = {}
                node = child
            node[leaf] = value
        return self._updates(key, value, caller_id)

    def delete(self, key: str) -> list[Update]:
        """Delete ``key`` and its subtree; KeyError when unset. The paramUpdates to send."""
        if key == GLOBAL_NS:
            raise KeyError("cannot delete root of parameter tree")
        *path, leaf = _parts(key)
        node: Any = self.root
        for part in path:
            if not isinstance(node, dict) or part not in node:
                raise KeyError(key)
            node = node[part]
        if not isinstance(node, dict) or leaf not in node:
            raise KeyError(key)
        del node[leaf]
        return self._updates(key, {}, None)

    def names(self) -> list[str]:
        """Full names of every leaf (empty dicts are not leaves)."""
        found: list[str] = []

        def walk(prefix: str, node: dict[str, Any]) -> None:
            for k, v in node.items():
                name = prefix + k
                if isinstance(v, dict):
                    walk(name + SEP, v)
                else:
                    found.append(name)

        walk(SEP, self.root)
        return found

    def search(self, ns: str, key: str) -> str | None:
        """Rosmaster's upward search from ``ns`` for the first element of ``key``."""
        if not key or is_private(key):
            raise Failure("invalid key")
        if not is_global(ns):
            raise Failure("namespace must be global")
        if is_global(key):
            return key if self.has(key) else None
        parts = _parts(key)
        head = parts[0]
        if self.has(canonicalize(ns + SEP + head)):
            return canonicalize(ns + SEP + key)
        spaces = _parts(ns)
        for i in range(1, len(spaces) + 1):
            base = spaces[:-i]
            if self.has(SEP + SEP.join([*base, head])):
                return SEP + SEP.join([*base, key])
        return None

    def _updates(self, key: str, value: Any, ignore: str | None) -> list[Update]:
        if not self.subscribers:
            return []
        changed = subscription_key(key)
        all_keys = _all_keys(changed, value) if isinstance(value, dict) else None
        updates: list[Update] = []
        for skey, subs in self.subscribers.items():
            if changed.startswith(skey):
                # The subscribed key, or something below it, changed: send the changed key.
                updates += [(cid, api, changed, value) for cid, api in subs if cid != ignore]
            elif all_keys is not None and skey.startswith(changed) and skey not in all_keys:
                # A dict replaced an ancestor and no longer holds the subscribed key.
                updates += [(cid, api, skey, {}) for cid, api in subs]
        if all_keys is not None:
            for skey in all_keys:
                if skey in self.subscribers:
                    sub_value = value
                    for part in _parts(skey[len(changed) :]):
                        sub_value = sub_value[part]
                    updates += [(cid, api, skey, sub_value) for cid, api in self.subscribers[skey]]
        return updates


def nesting(value: Any) -> int:
    """How many levels of dicts and lists ``value`` holds (0 for a scalar), without recursion."""
    deepest, level = 0, [(value, 0)]
    while level:
        item, depth = level.pop()
        children = (
            item.values() if isinstance(item, dict) else item if isinstance(item, list) else None
        )
        if children is None:
            continue
        deepest = max(deepest, depth + 1)
        if deepest > MAX_DEPTH:
            return deepest  # deep enough to refuse: no need to walk the rest
        level += [(child, depth + 1) for child in children]
    return deepest


def _all_keys(prefix: str, value: dict[str, Any]) -> set[str]:
    """Every key (with trailing slash) inside a dict set at ``prefix``."""
    keys: set[str] = set()
    for k, v in value.items():
        child = prefix + k + SEP
        keys.add(child)
        if isinstance(v, dict):
            keys |= _all_keys(child, v)
    return keys
