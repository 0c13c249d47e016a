"""Where ``bag export`` puts each table: the reversible key of a topic or bag (issue 38); its
writer on a thread of its own."""

from __future__ import annotations

from pathlib import Path

import pytest
from hypothesis import given, strategies as st

from rostools.bag.tables.layout import bag_key, part_path, table_key, topic_key, topic_of_key


def test_a_topic_key_is_readable_and_never_percent_or_slash() -> None:
    assert topic_key("/imu/data") == "imu.data"
    assert topic_key("/a_b/c2") == "a_b.c2"
    assert topic_key("/a.b") == "a~2eb"  # a literal dot is escaped: "." is a slash
    assert topic_key("/a b%/ü") == "a~20b~25.~c3~bc"
    assert topic_key("relative/x") == "~-relative.x"
    assert table_key("/imu", "6a62c6daae103f4ff57a132d6f95cec2") == "imu@6a62c6da"
    assert table_key("/imu", None) == "imu"


@given(st.text())
def test_every_topic_comes_back_from_its_key(topic: str) -> None:
    key = topic_key(topic)
    assert "/" not in key and "%" not in key and "=" not in key and "@" not in key
    assert topic_of_key(key) == topic
    assert topic_of_key(key + "@0123abcd") == topic


@given(st.text(min_size=1), st.text(min_size=1))
def test_two_topics_never_share_a_key(a: str, b: str) -> None:
    assert (topic_key(a) == topic_key(b)) == (a == b)


def test_a_bag_key_is_its_stem_escaped() -> None:
    assert bag_key(Path("runs/2024-05-01 run.1.bag")) == "2024-05-01~20run~2e1"
    assert bag_key("plain_name.mcap") == "plain_name"
    assert part_path(Path("out"), "imu", "a", "parquet") == Path(
        "out/topic=imu/bag=a/part-0.parquet"
    )


class _Failing:
    """A table writer whose second write fails."""

    def __init__(self) -> None:
        self.written: list[object] = []
        self.closed = False

    def write(self, batch: object) -> None:
        if self.written:
            raise OSError("disk full")
        self.written.append(batch)

    def close(self) -> None:
        self.closed = True


def test_a_writer_behind_raises_its_error_on_the_callers_thread_and_still_closes() -> None:
    from rostools.bag.tables.writers import Behind

    inner = _Failing()
    writer = Behind(inner)  # type: ignore[arg-type]
    with pytest.raises(OSError, match="disk full"):
        try:
            for batch in range(100):  # the error comes back by a later write, or by close
                writer.write(batch)  # type: ignore[arg-type]
        finally:
            writer.close()  # as export's does: it raises the error only if no write did
    assert inner.written == [0] and inner.closed
