"""pyarrow, imported on first use: the base install neither needs nor loads it."""

from __future__ import annotations

from typing import Any, Final

#: Arrow's lists, strings and binary values of one batch hold at most this many elements or
#: bytes (their offsets are 32-bit); ``BATCH_BYTES`` keeps batches far below it.
MAX_OFFSET: Final = (1 << 31) - 1


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


def from_numpy(pa: Any, values: Any, type_: Any = None) -> Any:
    """A 1-D numpy array as an Arrow array of ``type_`` (else its dtype's), sharing its buffer.

    Not ``pa.array``: given a numpy array, it imports pandas to check what it was given, which
    costs a command half a second when pandas is installed.
    """
    import numpy as np

    if values.dtype == np.bool_ or (type_ is not None and type_ == pa.bool_()):
        bits = np.packbits(values != 0, bitorder="little")  # Arrow's booleans are bits
        return pa.Array.from_buffers(pa.bool_(), len(values), [None, pa.py_buffer(bits)])
    values = np.ascontiguousarray(values)
    arrow_type = pa.from_numpy_dtype(values.dtype) if type_ is None else type_
    return pa.Array.from_buffers(arrow_type, len(values), [None, pa.py_buffer(values)])


def string_array(pa: Any, values: list[str]) -> Any:
    """Python strings as an Arrow string array, from one joined buffer (not ``pa.array``)."""
    import numpy as np

    joined = "".join(values)
    data = joined.encode()
    if len(data) == len(joined):  # ASCII: a character is a byte
        sizes = np.fromiter(map(len, values), np.int64, len(values))
    else:
        sizes = np.fromiter((len(v.encode()) for v in values), np.int64, len(values))
    return _strings(pa, sizes, data)


def repeated_string(pa: Any, text: str, rows: int) -> Any:
    """``text`` ``rows`` times, as an Arrow string array."""
    import numpy as np

    data = text.encode()
    return _strings(pa, np.full(rows, len(data), np.int64), data * rows)


def _strings(pa: Any, sizes: Any, data: bytes) -> Any:
    import numpy as np

    offsets = np.zeros(len(sizes) + 1, np.int64)
    np.cumsum(sizes, out=offsets[1:])
    if offsets[-1] > MAX_OFFSET:
        from rostools.errors import InvalidDataError

        raise InvalidDataError(f"{int(offsets[-1])} bytes of strings are too many for a batch")
    return pa.StringArray.from_buffers(
        len(sizes), pa.py_buffer(offsets.astype(np.int32)), pa.py_buffer(data)
    )
