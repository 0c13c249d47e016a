"""What the bag tools share: which messages they copy, and how they write them.

``filter``, ``convert``, ``compress`` and ``decompress`` (``ops``), ``merge`` and ``split`` take
one ``CopyOptions``, as their commands build it from the same options.
"""

from __future__ import annotations

from collections.abc import Callable, Collection
from dataclasses import dataclass
from typing import TYPE_CHECKING, Final

if TYPE_CHECKING:
    from rostools.bag.tools.rename import Renames

#: ``progress(done, total)`` is called about every this many messages (and at the end).
PROGRESS_EVERY: Final = 4096
#: Reports progress: messages done so far and the total the input holds.
Progress = Callable[[int, int], None]


@dataclass(frozen=True)
class CopyOptions:
    """Which messages a tool copies, and how it writes them.

    ``topics`` and ``start``/``end`` (ns, inclusive) select without decoding; ``expression``
    is Python over ``topic``, ``m`` and ``t`` as in ``rosbag filter`` (see ``ops.filter_bag``).
    They see the input's names; ``renames`` renames topics and types as they are written.
    ``compression`` and ``chunk_size`` are ``open_writer``'s (None: the format's default);
    ``overwrite`` lets the output replace a file; ``check_crcs`` as ``open_bag``'s.
    """

    topics: Collection[str] | None = None
    start: int | None = None
    end: int | None = None
    expression: str | None = None
    compression: str | None = None
    chunk_size: int | None = None
    overwrite: bool = False
    renames: Renames | None = None
    check_crcs: bool = True

    @property
    def selects(self) -> bool:
        """Whether some messages may be left out: a topic, time or expression filter."""
        return not (self.topics is None and self.start is None and self.end is None) or bool(
            self.expression
        )


#: Everything, as it is: the default of every tool.
ALL: Final = CopyOptions()
