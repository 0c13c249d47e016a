"""The Arrow schema of a topic's table, and its flat form (dotted names).

A table's columns are ``record_time`` (when the bag recorded the message, timestamp[ns]),
then every field of the message in order: the header, where the type has one, is the
``header`` struct like any nested message, so ``header.stamp`` names its stamp in SQL and in
the flat form. The type mapping is ``columns.py``'s (docs/tables.md lists it).
"""

from __future__ import annotations

from typing import Any, Final

from rostools.bag.tables.arrow import pyarrow

#: The column of the time the bag recorded each message.
RECORD_TIME: Final = "record_time"


def table_schema(fields: list[Any], *, flatten: bool = False) -> Any:
    """``record_time`` and the message's fields, nested or flattened."""
    pa = pyarrow()
    columns = [pa.field(RECORD_TIME, pa.timestamp("ns"), nullable=False), *fields]
    schema = pa.schema(columns)
    return flat_schema(schema) if flatten else schema


def flat_schema(schema: Any) -> Any:
    """Struct columns as their leaves, named with dots (``header.stamp``); lists stay lists."""
    pa = pyarrow()
    return pa.schema(list(_flat_fields(list(schema), "")))


def _flat_fields(fields: list[Any], prefix: str) -> Any:
    pa = pyarrow()
    for field in fields:
        name = prefix + field.name
        if pa.types.is_struct(field.type) and field.type.num_fields:
            yield from _flat_fields(list(field.type), name + ".")
        else:
            yield field.with_name(name)


def flat_arrays(arrays: list[Any], fields: list[Any]) -> list[Any]:
    """The arrays of ``flat_schema``'s columns, from the nested ones (no copy)."""
    pa = pyarrow()
    out: list[Any] = []
    for array, field in zip(arrays, fields, strict=True):
        if pa.types.is_struct(field.type) and field.type.num_fields:
            children = [array.field(i) for i in range(field.type.num_fields)]
            out += flat_arrays(children, list(field.type))
        else:
            out.append(array)
    return out
