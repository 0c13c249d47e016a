"""Bags as Arrow tables (issue 38; the extras ``rostools[arrow]`` and ``rostools[sql]``).

A message type as an Arrow schema, decoders generated per type that write straight into
columns, record batches streamed per topic, the dataset export and the SQL views.

Imports ``formats``, never ``live`` or ``tools``; pyarrow and duckdb only inside functions,
so that the base install neither needs nor loads them.
"""
