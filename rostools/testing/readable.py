"""A failing helper of the plugin shows the test's line and the message, not rostools' frames.

pytest leaves out of a failure's traceback every frame that sets ``__tracebackhide__``. The
helpers set it, and ``readable`` cuts what lies below a helper from an error of ours raised
deeper down (a master that cannot be reached, a type that does not exist): its message
names what went wrong, as the CLI's one line does.
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from typing import ParamSpec, TypeVar

from rostools.errors import RostoolsError

P = ParamSpec("P")
T = TypeVar("T")


def readable(helper: Callable[P, T]) -> Callable[P, T]:
    """``helper``, whose failures show where the test called it and what went wrong."""

    @functools.wraps(helper)
    def called(*args: P.args, **kwargs: P.kwargs) -> T:
        __tracebackhide__ = True
        try:
            return helper(*args, **kwargs)
        except RostoolsError as err:
            raise err.with_traceback(None) from None

    return called
