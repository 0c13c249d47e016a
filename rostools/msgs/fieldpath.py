"""Field paths: ``pose/pose/position``, ``transforms[0]/header``, ``ranges[::2]``.

``rostopic echo /topic/field`` takes the part after the topic; so do we. A path is checked
against the type before any message arrives, so a typo fails at once instead of printing
``no field named x`` for every message as rostopic does.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from rostools.errors import UsageError
from rostools.msgs.codegen import attr_name
from rostools.msgs.spec import BUILTIN_TYPES, Field
from rostools.msgs.store import TypeStore


@dataclass(frozen=True)
class Step:
    """One path element: a field name and an optional index or slice."""

    name: str
    index: int | slice | None


def _parse_index(text: str, step: str) -> int | slice:
    parts = text.split(":")
    if len(parts) > 3 or text == "":
        raise UsageError(f"bad index [{text}] in field path element {step!r}")
    try:
        values = [int(p) if p else None for p in parts]
    except ValueError:
        raise UsageError(f"bad index [{text}] in field path element {step!r}") from None
    if len(parts) == 1:
        assert values[0] is not None
        return values[0]
    return slice(*values)


def parse(path: str) -> list[Step]:
    """Split ``a/b[1]/c[2:]`` into steps."""
    steps: list[Step] = []
    for element in (e for e in path.split("/") if e):
        if "[" in element:
            name, _, rest = element.partition("[")
            if not rest.endswith("]"):
                raise UsageError(f"missing ']' in field path element {element!r}")
            steps.append(Step(name, _parse_index(rest[:-1], element)))
        else:
            steps.append(Step(element, None))
    return steps


@dataclass(frozen=True)
class FieldPath:
    """A parsed path with the type of what it yields."""

    text: str
    steps: tuple[Step, ...]
    result: Field  # the value type; an array when any step sliced

    def get(self, msg: Any) -> Any:
        """The value at the path (a list when a step slices)."""
        return _get(msg, self.steps)


def _get(value: Any, steps: tuple[Step, ...]) -> Any:
    for i, step in enumerate(steps):
        value = getattr(value, attr_name(step.name))
        if step.index is not None:
            value = value[step.index]
            if isinstance(step.index, slice):
                rest = steps[i + 1 :]
                return [_get(v, rest) for v in value] if rest else list(value)
    return value


def resolve(store: TypeStore, msg_type: str, path: str) -> FieldPath:
    """Check ``path`` against ``msg_type`` and work out what it yields."""
    steps = tuple(parse(path))
    current = Field("", msg_type, msg_type, False, None)
    sliced = False
    for step in steps:
        if current.is_array or current.base in BUILTIN_TYPES:
            raise UsageError(f"no field named {step.name} in {current.type} (path {path!r})")
        spec = store.msg(current.base)
        found = next((f for f in spec.fields if f.name == step.name), None)
        if found is None:
            names = ", ".join(f.name for f in spec.fields) or "none"
            raise UsageError(
                f"no field named {step.name} in {spec.name} (path {path!r})",
                hint=f"its fields are: {names}",
            )
        current = found
        if step.index is not None:
            if not current.is_array:
                raise UsageError(f"{step.name} in {spec.name} is not an array (path {path!r})")
            sliced = sliced or isinstance(step.index, slice)
            current = Field(current.name, current.base, current.base, False, None)
    if sliced:
        if current.is_array:
            raise UsageError(f"a sliced path cannot end in the array {current.name} ({path!r})")
        current = Field(current.name, current.base + "[]", current.base, True, None)
    return FieldPath(path, steps, current)
