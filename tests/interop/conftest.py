"""Fixtures the interop modules share."""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.support import cppbuild


@pytest.fixture(scope="module")
def node_peers() -> Iterator[dict[str, Path]]:
    """The roscpp talker, listener and add_two_ints_server, built once a module."""
    if (reason := cppbuild.cpp_missing()) is not None:
        pytest.skip(reason)
    yield cppbuild.build_many(["talker", "listener", "add_two_ints_server"])
