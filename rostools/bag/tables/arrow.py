"""pyarrow, imported on first use: the base install neither needs nor loads it."""

from __future__ import annotations

from typing import Any


def pyarrow(what: str = "") -> Any:
    """The ``pyarrow`` module, or a ``MissingExtraError`` naming ``rostools[arrow]`` (exit 2).

    ``what`` names the feature in the line ("bag export needs pyarrow: pip install ...").
    """
    try:
        import pyarrow as pa
    except ImportError:
        from rostools.errors import MissingExtraError

        raise MissingExtraError("pyarrow", "arrow", what=what) from None
    return pa
