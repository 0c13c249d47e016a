"""YAML that users give us (``pub``, ``service call``, ``param set/load``), parsed safely.

- Fast: libyaml when PyYAML has it, and a JSON fast path for flow-style text (a
  million-number array: 0.1 s, where PyYAML takes 43 s in Python and 7.5 s in C), with YAML
  1.1's reading of numbers, so the result is the same.
- Bounded: aliases are shared, not copied, by PyYAML, but everything downstream (XML-RPC,
  serialisation) expands them. Nine levels of nine aliases, 300 bytes, expand to 387 million
  values, so the expanded size and the depth are capped.
- One line: every failure is a ``UsageError`` naming the source and the place.
"""

from __future__ import annotations

import json
import re
from typing import Any

import yaml

from rostools.errors import UsageError

#: Values a document may expand to once its aliases are followed.
MAX_VALUES = 10_000_000
#: How deep a document may nest: the parameter server's limit, and far beyond any message.
MAX_DEPTH = 100
#: PyYAML's SafeLoader, in C when it was built with libyaml.
SafeLoader: type[yaml.SafeLoader] = getattr(yaml, "CSafeLoader", yaml.SafeLoader)
#: The numbers YAML 1.1 reads as floats (PyYAML's resolver); JSON's ``1e5`` is a string there.
_YAML_FLOAT = re.compile(r"[-+]?[0-9][0-9_]*\.[0-9_]*(?:[eE][-+][0-9]+)?")


def load(
    text: str, source: str, loader: type[yaml.SafeLoader] = SafeLoader, max_values: int = MAX_VALUES
) -> Any:
    """One YAML document (``None`` for an empty one)."""
    docs = load_all(text, source, loader, max_values)
    if len(docs) > 1:
        raise UsageError(f"bad YAML in {source}: one document expected, got {len(docs)}")
    return docs[0] if docs else None


def load_all(
    text: str, source: str, loader: type[yaml.SafeLoader] = SafeLoader, max_values: int = MAX_VALUES
) -> list[Any]:
    """Every document of a YAML stream, checked against ``max_values`` and ``MAX_DEPTH``."""
    try:
        docs = _fast(text)
        if docs is None:
            docs = list(yaml.load_all(text, Loader=loader))
    except yaml.YAMLError as err:
        raise UsageError(f"bad YAML in {source}: {_problem(err)}") from err
    except RecursionError:
        raise UsageError(f"bad YAML in {source}: nested deeper than {MAX_DEPTH} levels") from None
    except ValueError as err:  # Python refuses to read an integer of thousands of digits
        problem = "an integer too long to read" if "digits" in str(err) else str(err)
        raise UsageError(f"bad YAML in {source}: {problem}") from err
    for doc in docs:
        check_size(doc, source, max_values)
    return docs


def _fast(text: str) -> list[Any] | None:
    """A flow-style document read as JSON, with YAML's numbers; None when it is not JSON."""
    head = text.lstrip()[:1]
    if head not in ("[", "{"):
        return None
    try:
        return [
            json.loads(
                text,
                parse_float=lambda s: float(s) if _YAML_FLOAT.fullmatch(s) else s,
                parse_constant=lambda s: s,  # NaN, Infinity: plain strings in YAML
            )
        ]
    except json.JSONDecodeError:
        return None


def check_size(value: Any, source: str, max_values: int = MAX_VALUES) -> None:
    """Refuse a value that expands past ``max_values`` or nests past ``MAX_DEPTH``.

    Shared lists and dicts (YAML aliases) are measured once each, so an alias bomb is found
    at the cost of its few distinct nodes. A value that contains itself is refused too.
    """
    sizes: dict[int, tuple[int, int]] = {}  # id -> (expanded values, depth)
    open_: set[int] = set()
    stack: list[tuple[Any, bool]] = [(value, False)]
    while stack:
        item, children_done = stack.pop()
        if not isinstance(item, list | dict) or (id(item) in sizes and not children_done):
            continue
        members = list(item.values()) if isinstance(item, dict) else item
        inner = [m for m in members if isinstance(m, list | dict)]
        if not children_done:
            if id(item) in open_:
                raise UsageError(f"bad YAML in {source}: a value that contains itself")
            open_.add(id(item))
            stack.append((item, True))
            stack += [(m, False) for m in inner]
            continue
        open_.discard(id(item))
        size = len(members) + sum(sizes[id(m)][0] for m in inner)
        depth = 1 + max((sizes[id(m)][1] for m in inner), default=0)
        if depth > MAX_DEPTH:
            raise UsageError(f"bad YAML in {source}: nested deeper than {MAX_DEPTH} levels")
        if size > max_values:
            raise UsageError(
                f"bad YAML in {source}: it expands to more than {max_values:,} values "
                "(aliases of aliases?)"
            )
        sizes[id(item)] = (size, depth)


def _problem(err: yaml.YAMLError) -> str:
    """A parse error in one line, with its place."""
    mark = getattr(err, "problem_mark", None)
    where = f" (line {mark.line + 1}, column {mark.column + 1})" if mark is not None else ""
    problem = getattr(err, "problem", None) or str(err).splitlines()[0]
    return f"{problem}{where}"
