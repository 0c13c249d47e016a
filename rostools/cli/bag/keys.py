"""Keys read from a terminal on stdin while a bag command runs (play's space, snapshot's s)."""

from __future__ import annotations

import contextlib
import os
import sys
from collections.abc import Callable, Iterator, Mapping
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import asyncio


@contextlib.contextmanager
def keyboard(
    keys: Mapping[str, Callable[[], object]], loop: asyncio.AbstractEventLoop
) -> Iterator[bool]:
    """Call ``keys[key]`` for each key typed, read without echo; yields False if no terminal."""
    if not sys.stdin.isatty():
        yield False
        return
    import termios
    import tty

    fd = sys.stdin.fileno()
    saved = termios.tcgetattr(fd)

    def on_key() -> None:
        for key in os.read(fd, 32).decode(errors="replace"):
            action = keys.get(key)
            if action is not None:
                action()

    tty.setcbreak(fd)
    loop.add_reader(fd, on_key)
    try:
        yield True
    finally:
        loop.remove_reader(fd)
        termios.tcsetattr(fd, termios.TCSADRAIN, saved)
