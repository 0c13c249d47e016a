"""Time-ordered merging of blocks whose time ranges overlap, and of several readers."""

from __future__ import annotations

from hypothesis import given, strategies as st

from rostools.bag.formats.model import Connection
from rostools.bag.formats.ordering import Block, Entry, merge, ordered

CONNS = [
    Connection(i, f"/t{i}", "std_msgs/Empty", "d41d8cd98f00b204e9800998ecf8427e", "")
    for i in range(3)
]

blocks_of_times = st.lists(
    st.lists(st.tuples(st.integers(0, 50), st.integers(0, 2)), min_size=0, max_size=30),
    max_size=8,
)


def make_blocks(
    spec: list[list[tuple[int, int]]],
) -> tuple[list[Block], list[tuple[int, int, int, int]]]:
    """Blocks from (time, rank) lists, and the order every message must come out in."""
    blocks, expected = [], []
    loads: list[int] = []
    for order, items in enumerate(spec):
        entries: list[Entry] = sorted(
            (t, rank, pos, CONNS[rank], memoryview(b"%d/%d" % (order, pos)))
            for pos, (t, rank) in enumerate(items)
        )
        expected += [(t, rank, order, pos) for t, rank, pos, _, _ in entries]

        def load(entries: list[Entry] = entries, order: int = order) -> list[Entry]:
            loads.append(order)
            return entries

        blocks.append(Block(entries[0][0] if entries else 0, order, load))
    expected.sort()
    return blocks, expected


@given(blocks_of_times)
def test_ordered_yields_time_order_with_rosbag_tie_breaks(
    spec: list[list[tuple[int, int]]],
) -> None:
    blocks, expected = make_blocks(spec)
    got = [(t, conn.id, bytes(data)) for conn, t, data in ordered(blocks)]
    assert got == [(t, rank, b"%d/%d" % (order, pos)) for t, rank, order, pos in expected]


def test_disjoint_blocks_are_loaded_one_at_a_time() -> None:
    opened: list[int] = []

    def block(order: int, times: list[int]) -> Block:
        entries: list[Entry] = [(t, 0, i, CONNS[0], memoryview(b"")) for i, t in enumerate(times)]

        def load() -> list[Entry]:
            opened.append(order)
            return entries

        return Block(times[0], order, load)

    stream = ordered([block(1, [10, 11, 12]), block(0, [1, 2, 3]), block(2, [20])])
    assert next(stream)[1] == 1
    assert opened == [0]  # the later blocks are not read before they are needed
    assert [t for _, t, _ in stream] == [2, 3, 10, 11, 12, 20]
    assert opened == [0, 1, 2]


def test_merge_prefers_the_first_stream_on_ties() -> None:
    a = iter([(CONNS[0], 1, memoryview(b"a1")), (CONNS[0], 5, memoryview(b"a5"))])
    b = iter([(CONNS[1], 1, memoryview(b"b1")), (CONNS[1], 3, memoryview(b"b3"))])
    assert [bytes(d) for _, _, d in merge([a, b])] == [b"a1", b"b1", b"b3", b"a5"]
