"""Fixtures the interop modules share."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.support import cppbuild
from tests.support.procs import Proc


@pytest.fixture(scope="module")
def node_peers() -> Iterator[dict[str, Path]]:
    """The roscpp talker, listener and add_two_ints_server, built once a module."""
    if (reason := cppbuild.cpp_missing()) is not None:
        pytest.skip(reason)
    yield cppbuild.build_many(["talker", "listener", "add_two_ints_server"])


def start_node_peers(peers: dict[str, Path], env: dict[str, str]) -> tuple[Proc, Proc, Proc]:
    """The roscpp talker (/cpp_chatter at 20 Hz), listener (/to_roscpp) and a throwing
    add_two_ints_server, started; stop each by ``Proc.stop``."""
    return (
        Proc([str(peers["talker"]), "/cpp_chatter", "--rate", "20"], env=env),
        Proc([str(peers["listener"]), "/to_roscpp"], env=env),
        Proc([str(peers["add_two_ints_server"]), "--mode", "throw"], env=env),
    )
