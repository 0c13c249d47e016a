"""Time-ordered iteration over blocks (chunks) whose time ranges may overlap.

Both formats store messages in blocks that are sorted internally but not necessarily in time
order across the file (``example-unsorted-chunks.bag``; MCAP chunks from several writers).
Blocks are loaded lazily in order of their start time, and only blocks that overlap the
current position are held at once; the common case of disjoint blocks streams each block with
no heap at all.
"""

from __future__ import annotations

import heapq
import itertools
from bisect import bisect_left
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass
from operator import itemgetter
from typing import TYPE_CHECKING, Any, Literal, overload

if TYPE_CHECKING:
    from rostools.bag.formats.model import Connection

#: One message of a block: (time ns, rank, position in the block, connection, data), and for
#: MCAP also (sequence, publish time ns). The three ints are unique within a block, so sorting
#: never compares the rest. Rank breaks ties between connections the way rosbag does (order of
#: the connection records).
Entry = (
    tuple[int, int, int, "Connection", memoryview]
    | tuple[int, int, int, "Connection", memoryview, int, int]
)
#: What readers yield: the connection, the receive time in ns, the raw serialized message.
RawMessage = tuple["Connection", int, memoryview]


@dataclass(frozen=True)
class Block:
    """A stored group of messages: its first time, file order, and how to load its entries.

    ``load`` returns the block's entries (already filtered) sorted by ``Entry`` order.
    """

    start_ns: int
    order: int
    load: Callable[[], list[Entry]]


@overload
def ordered(blocks: Iterable[Block], whole: Literal[False] = False) -> Iterator[RawMessage]: ...
@overload
def ordered(blocks: Iterable[Block], whole: Literal[True]) -> Iterator[Entry]: ...


def ordered(blocks: Iterable[Block], whole: bool = False) -> Iterator[Any]:
    """Every entry of every block, in time order (ties: rank, block order, position).

    Each as (connection, time, data), or with ``whole`` the entry itself.
    """
    todo = sorted(blocks, key=lambda b: (b.start_ns, b.order))
    count = len(todo)
    # Heap items: (time, rank, block order, position, index in entries, entries).
    heap: list[tuple[int, int, int, int, int, list[Entry]]] = []
    i = 0
    while True:
        # Admit every block that may hold something at or before the current head.
        while i < count and (not heap or todo[i].start_ns <= heap[0][0]):
            block = todo[i]
            entries = block.load()
            i += 1
            if entries:
                e = entries[0]
                heapq.heappush(heap, (e[0], e[1], block.order, e[2], 0, entries))
        if not heap:
            return
        if len(heap) == 1:
            # One block open: stream it up to where the next block starts.
            _, _, order, _, k, entries = heap[0]
            cut = len(entries) if i >= count else bisect_left(entries, (todo[i].start_ns,), lo=k)
            run = entries[k:cut] if k or cut < len(entries) else entries
            if whole:
                yield from run
            else:
                for e in run:
                    yield e[3], e[0], e[4]
            if cut >= len(entries):
                heap.clear()
            else:
                e = entries[cut]
                heap[0] = (e[0], e[1], order, e[2], cut, entries)
            continue
        _, _, order, _, k, entries = heapq.heappop(heap)
        e = entries[k]
        yield e if whole else (e[3], e[0], e[4])
        k += 1
        if k < len(entries):
            e = entries[k]
            heapq.heappush(heap, (e[0], e[1], order, e[2], k, entries))


def out_of_order(times: Iterable[int]) -> int:
    """How many times in a block come before the one stored ahead of them."""
    return sum(1 for a, b in itertools.pairwise(times) if b < a)


def merge(streams: Iterable[Iterator[RawMessage]]) -> Iterator[RawMessage]:
    """Several readers' message streams merged in time order (``bag play a.bag b.bag``).

    Ties go to the earlier stream (``heapq.merge`` is stable), as ``rosbag play`` does.
    """
    return heapq.merge(*streams, key=itemgetter(1))
