"""The run-time values of messages: ``Message``, ``Time`` and ``Duration``.

They behave like genpy's where a user can see it (``--filter`` expressions, ``rostopic echo``
output): fields are attributes, times have ``secs``/``nsecs``, ``to_sec()`` and ``to_nsec()``.
Generated message classes (``rostools.msgs.codec``) derive from ``Message``.
"""

from __future__ import annotations

import time as _time
from typing import Any, ClassVar, TypeVar

_NS = 1_000_000_000
_T = TypeVar("_T", bound="_TVal")


class _TVal:
    """A (secs, nsecs) pair, kept canonical with 0 <= nsecs < 1e9 as genpy keeps it."""

    __slots__ = ("nsecs", "secs")

    def __init__(self, secs: int = 0, nsecs: int = 0) -> None:
        carry, nsecs = divmod(int(nsecs), _NS)
        self.secs = int(secs) + carry
        self.nsecs = nsecs

    @classmethod
    def from_sec(cls: type[_T], seconds: float) -> _T:
        """Build from float seconds."""
        secs = int(seconds // 1)
        return cls(secs, round((seconds - secs) * _NS))

    @classmethod
    def from_nsec(cls: type[_T], nanoseconds: int) -> _T:
        """Build from integer nanoseconds."""
        secs, nsecs = divmod(int(nanoseconds), _NS)
        return cls(secs, nsecs)

    def to_sec(self) -> float:
        """Seconds as a float."""
        return self.secs + self.nsecs / 1e9

    def to_nsec(self) -> int:
        """Nanoseconds as an int."""
        return self.secs * _NS + self.nsecs

    def is_zero(self) -> bool:
        """True for zero."""
        return self.secs == 0 and self.nsecs == 0

    def __eq__(self, other: object) -> bool:
        if isinstance(other, _TVal):
            return type(self) is type(other) and self.to_nsec() == other.to_nsec()
        return NotImplemented

    def __lt__(self, other: _TVal) -> bool:
        return self.to_nsec() < other.to_nsec()

    def __le__(self, other: _TVal) -> bool:
        return self.to_nsec() <= other.to_nsec()

    def __hash__(self) -> int:
        return hash((type(self).__name__, self.to_nsec()))

    def __str__(self) -> str:
        return str(self.to_nsec())

    def __repr__(self) -> str:
        return f"{type(self).__name__}({self.secs}, {self.nsecs})"


class Duration(_TVal):
    """A ROS ``duration``."""

    __slots__ = ()

    def __add__(self, other: Duration) -> Duration:
        return Duration.from_nsec(self.to_nsec() + other.to_nsec())

    def __sub__(self, other: Duration) -> Duration:
        return Duration.from_nsec(self.to_nsec() - other.to_nsec())

    def __neg__(self) -> Duration:
        return Duration.from_nsec(-self.to_nsec())


class Time(_TVal):
    """A ROS ``time``."""

    __slots__ = ()

    @classmethod
    def now(cls) -> Time:
        """Wall-clock time."""
        return cls.from_nsec(_time.time_ns())

    def __add__(self, other: Duration) -> Time:
        return Time.from_nsec(self.to_nsec() + other.to_nsec())

    def __sub__(self, other: _TVal) -> Any:
        if isinstance(other, Time):
            return Duration.from_nsec(self.to_nsec() - other.to_nsec())
        return Time.from_nsec(self.to_nsec() - other.to_nsec())


def _same(a: Any, b: Any) -> bool:
    # Decoded arrays are tuples (as in genpy); arrays built by hand are often lists.
    if isinstance(a, tuple | list) and isinstance(b, tuple | list):
        return len(a) == len(b) and all(_same(x, y) for x, y in zip(a, b, strict=True))
    return bool(a == b)


class Message:
    """Base of every generated message class."""

    __slots__: ClassVar[tuple[str, ...]] = ()
    _type: ClassVar[str] = ""
    _md5sum: ClassVar[str] = ""
    _full_text: ClassVar[str] = ""
    _has_header: ClassVar[bool] = False
    _slot_types: ClassVar[tuple[str, ...]] = ()
    _fields: ClassVar[tuple[str, ...]] = ()  # ROS field names (slots may carry a '_' suffix)

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        """Field values in order or by name (generated per class; defaults for the rest)."""
        raise TypeError("Message is abstract; use a class from rostools.msgs.codec")

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        return all(_same(getattr(self, s), getattr(other, s)) for s in self.__slots__)

    __hash__ = None  # type: ignore[assignment]  # mutable, like genpy messages

    def __repr__(self) -> str:
        inner = ", ".join(f"{s}={getattr(self, s)!r}" for s in self.__slots__)
        return f"{self._type}({inner})"

    def serialize(self) -> bytes:
        """The message in ROS 1 wire format (generated per class)."""
        raise NotImplementedError

    @classmethod
    def deserialize(cls, data: bytes | memoryview) -> Any:
        """Decode ROS 1 wire bytes into an instance (generated per class)."""
        raise NotImplementedError
