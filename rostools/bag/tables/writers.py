"""The files of ``bag export``: record batches streamed into Parquet, Arrow IPC, CSV or NDJSON.

Each writer takes batches as they come and keeps none, so memory stays one batch whatever
the size of the bag. pyarrow is imported when a writer is opened.

- Parquet: ``pyarrow.parquet.ParquetWriter``, zstd pages, dictionaries for strings only,
  the Arrow schema kept; written on a thread of its own, beside the decoding.
- Arrow: the IPC file format (Feather v2), uncompressed, which DuckDB, Polars and
  pyarrow.dataset map without copying.
- CSV: flat columns (``bag export`` flattens for CSV); a column CSV cannot hold (a list, a
  struct left in a list) is JSON text, and bytes (``uint8[]``) are base64. Times are ISO 8601
  with nanoseconds (UTC, no zone written); durations integer nanoseconds.
- NDJSON: one JSON object a line. Times and durations are integer nanoseconds (JSON has no
  time), bytes base64, and NaN and infinities the strings ``"nan"``, ``"inf"``, ``"-inf"``,
  as every JSON rostools writes.
"""

from __future__ import annotations

import base64
import json
import math
import queue
import threading
from pathlib import Path
from typing import TYPE_CHECKING, Any, Final, Protocol

if TYPE_CHECKING:
    import pyarrow as pa

#: File formats and their file suffixes.
FORMATS: Final = {"parquet": "parquet", "arrow": "arrow", "csv": "csv", "ndjson": "ndjson"}
#: Batches a writer on its own thread may hold queued (memory: this many batches more).
BEHIND_BATCHES: Final = 1


class TableWriter(Protocol):
    """One table's file, written a batch at a time."""

    def write(self, batch: pa.RecordBatch) -> None:
        """Append ``batch``'s rows."""

    def close(self) -> None:
        """Finish the file (its footer)."""


def open_table(fmt: str, path: Path, schema: pa.Schema) -> TableWriter:
    """A writer of ``fmt`` creating ``path`` for batches of ``schema``."""
    path.parent.mkdir(parents=True, exist_ok=True)
    if fmt == "parquet":
        import pyarrow.parquet as pq

        text = _string_columns(schema)
        return Behind(pq.ParquetWriter(str(path), schema, compression="zstd", use_dictionary=text))
    if fmt == "arrow":
        import pyarrow as pa

        return _Ipc(pa.ipc.new_file(str(path), schema))
    if fmt == "csv":
        return _Csv(path, schema)
    return _Ndjson(path, schema)


def _string_columns(schema: pa.Schema) -> list[str]:
    """The Parquet paths of ``schema``'s string columns: the ones a dictionary is for.

    Frame ids, names and labels repeat; numbers rarely do, and trying a dictionary for each
    of them doubled the time an Imu table took to write (zstd packs what repeats anyway).
    """
    import pyarrow as pa
    import pyarrow.parquet as pq

    sink = pa.BufferOutputStream()
    pq.ParquetWriter(sink, schema).close()  # the schema alone, as Parquet lays it out
    columns = pq.ParquetFile(pa.BufferReader(sink.getvalue())).schema
    return [
        c.path for c in map(columns.column, range(len(columns))) if c.logical_type.type == "STRING"
    ]


class Behind:
    """A writer run on a thread of its own, a batch or two behind the caller.

    Parquet's encoding and compression run in C++ without the GIL: on a thread they overlap
    the decoding of the next batch (the export's other half). An error of the writer is
    raised once, by the next ``write`` or by ``close``; the batches after it are dropped.
    """

    def __init__(self, writer: TableWriter) -> None:
        self.writer = writer
        self.queue: queue.Queue[Any] = queue.Queue(maxsize=BEHIND_BATCHES)
        self.error: BaseException | None = None
        self.told = False  # the error was raised to the caller once
        self.thread = threading.Thread(target=self._run, name="table-writer", daemon=True)
        self.thread.start()

    def _run(self) -> None:
        while (batch := self.queue.get()) is not None:
            if self.error is None:
                try:
                    self.writer.write(batch)
                except BaseException as err:  # noqa: BLE001 - raised on the caller's thread
                    self.error = err

    def _raise(self) -> None:
        if self.error is not None and not self.told:
            self.told = True
            raise self.error

    def write(self, batch: pa.RecordBatch) -> None:
        """Queue ``batch`` (waits while ``BEHIND_BATCHES`` are queued)."""
        self._raise()
        self.queue.put(batch)

    def close(self) -> None:
        """Write what is queued, then finish the file."""
        self.queue.put(None)
        self.thread.join()
        try:
            self._raise()
        finally:
            self.writer.close()


class _Ipc:
    def __init__(self, writer: Any) -> None:
        self.writer = writer

    def write(self, batch: pa.RecordBatch) -> None:
        self.writer.write_batch(batch)

    def close(self) -> None:
        self.writer.close()


def _plain(kind: pa.DataType) -> pa.DataType:
    """``kind`` with every time and duration an int64 of ns, so to_pylist keeps nanoseconds."""
    import pyarrow as pa

    if pa.types.is_timestamp(kind) or pa.types.is_duration(kind):
        return pa.int64()
    if pa.types.is_struct(kind):
        return pa.struct([f.with_type(_plain(f.type)) for f in kind])
    if pa.types.is_fixed_size_list(kind):
        return pa.list_(_plain(kind.value_type), kind.list_size)
    if pa.types.is_large_list(kind):
        return pa.large_list(_plain(kind.value_type))
    if pa.types.is_list(kind):
        return pa.list_(_plain(kind.value_type))
    return kind


def _json_value(value: Any) -> Any:
    """``value`` from to_pylist as JSON data: bytes in base64, NaN and infinities as text."""
    if isinstance(value, float) and not math.isfinite(value):
        return "nan" if math.isnan(value) else ("inf" if value > 0 else "-inf")
    if isinstance(value, bytes):
        return base64.b64encode(value).decode("ascii")
    if isinstance(value, dict):
        return {k: _json_value(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_json_value(v) for v in value]
    return value


def _dumps(value: Any) -> str:
    try:  # the common case: nothing to change
        return json.dumps(value, separators=(",", ":"), ensure_ascii=False, allow_nan=False)
    except (TypeError, ValueError):
        return json.dumps(_json_value(value), separators=(",", ":"), ensure_ascii=False)


def _is_binary(kind: pa.DataType) -> bool:
    import pyarrow as pa

    t = pa.types
    return bool(t.is_binary(kind) or t.is_large_binary(kind) or t.is_fixed_size_binary(kind))


def _is_nested(kind: pa.DataType) -> bool:
    import pyarrow as pa

    t = pa.types
    return bool(t.is_struct(kind) or t.is_list(kind) or t.is_large_list(kind)
                or t.is_fixed_size_list(kind) or t.is_map(kind))  # fmt: skip


class _Csv:
    """CSV through pyarrow's writer; the columns it cannot write are made text first."""

    def __init__(self, path: Path, schema: pa.Schema) -> None:
        import pyarrow as pa
        import pyarrow.csv as pcsv

        self.text = [i for i, f in enumerate(schema) if _is_nested(f.type) or _is_binary(f.type)]
        fields = [f.with_type(pa.string()) if i in self.text else f for i, f in enumerate(schema)]
        self.schema = pa.schema(fields)
        self.writer = pcsv.CSVWriter(str(path), self.schema)

    def write(self, batch: pa.RecordBatch) -> None:
        import pyarrow as pa

        columns = list(batch.columns)
        for i in self.text:
            column = columns[i]
            if _is_binary(column.type):
                values = [None if v is None else base64.b64encode(v).decode("ascii")
                          for v in column.to_pylist()]  # fmt: skip
            else:
                plain = column.cast(_plain(column.type))
                values = [None if v is None else _dumps(v) for v in plain.to_pylist()]
            columns[i] = pa.array(values, pa.string())
        self.writer.write_batch(pa.record_batch(columns, schema=self.schema))

    def close(self) -> None:
        self.writer.close()


class _Ndjson:
    def __init__(self, path: Path, schema: pa.Schema) -> None:
        import pyarrow as pa

        self.plain = pa.schema([f.with_type(_plain(f.type)) for f in schema])
        self.file = path.open("w", encoding="utf-8")

    def write(self, batch: pa.RecordBatch) -> None:
        import pyarrow as pa

        # through a table: RecordBatch.cast is pyarrow 16's, the extra allows 14
        rows = pa.Table.from_batches([batch]).cast(self.plain).to_pylist()
        self.file.write("".join(_dumps(row) + "\n" for row in rows))

    def close(self) -> None:
        self.file.close()
