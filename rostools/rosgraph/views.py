"""``Record``: plain data classes for the graph views, without ``dataclasses``.

``dataclasses`` imports ``inspect`` (and ``ast``, ``dis``, ``tokenize``): 15 ms of start-up
for every command that shows topics or nodes, most of what such a command costs beside its
master calls. A record names its fields in ``__slots__`` and writes its own ``__init__``;
this base compares, hashes and shows it by those fields, as a dataclass would.
"""

from __future__ import annotations

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from typing import Any


class Record:
    """A value object: equal to another of its class with equal fields (``__slots__``)."""

    __slots__: tuple[str, ...] = ()

    def fields(self) -> tuple[Any, ...]:
        """The values of the fields, in order."""
        return tuple(getattr(self, name) for name in self.__slots__)

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        assert isinstance(other, Record)
        return self.fields() == other.fields()

    def __hash__(self) -> int:
        return hash(self.fields())  # a TypeError for a record that holds lists, as it should

    def __repr__(self) -> str:
        shown = ", ".join(f"{name}={getattr(self, name)!r}" for name in self.__slots__)
        return f"{type(self).__name__}({shown})"
