"""One type's messages in every form a command prints them: the one per-connection renderer.

``topic echo`` (live and ``-b``), ``bag cat``, ``service call`` and the action commands each
print the messages of one connection (or one service, or one action's part) of one type, as
its definition says. A ``Renderer`` is built once for that type and compiles, on first use,
only the forms a command asks for: rostopic's text, plain data (YAML), compact JSON, and CSV
rows with their header. What each command adds (echo's filter and ``-n``, cat's envelope,
the request beside the response) stays in the command.
"""

from __future__ import annotations

import functools

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from collections.abc import Callable
    from typing import Any

    from rostools.msgs.codec import Codec
    from rostools.msgs.plain import CsvOptions
    from rostools.msgs.spec import Field
    from rostools.msgs.store import TypeStore
    from rostools.msgs.text import TextOptions


class Renderer:
    """Messages of ``type_name`` (or the value at ``field`` in each) as text, data or CSV."""

    def __init__(
        self,
        codec: Codec,
        type_name: str,
        field: str = "",
        text_options: TextOptions | None = None,
        csv_options: CsvOptions | None = None,
    ) -> None:
        from rostools.msgs import plain, text

        self.codec = codec
        self.type_name = type_name
        self.value_type: Field = text.message_type(type_name)
        self.get: Callable[[Any], Any] | None = None
        if field:
            from rostools.msgs import fieldpath

            path = fieldpath.resolve(codec.store, type_name, field)
            self.value_type, self.get = path.result, path.get
        self.text_options = text_options or text.TextOptions()
        self.csv_options = csv_options or plain.CsvOptions()

    @classmethod
    def learnt(
        cls, base: TypeStore, type_name: str, md5sum: str, definition: str, **options: Any
    ) -> Renderer:
        """The renderer of a type as a publisher or a bag defines it (``msgs.learnt``)."""
        from rostools.msgs import learnt

        return cls(learnt.codec(base, type_name, md5sum, definition), type_name, **options)

    @functools.cached_property
    def decode(self) -> Callable[[Any, int], tuple[Any, int]]:
        """``decode(data, offset) -> (message, end)``."""
        return self.codec.decoder(self.type_name)

    def value(self, msg: Any) -> Any:
        """What is shown of ``msg``: the message, or the value its field path names."""
        return msg if self.get is None else self.get(msg)

    @functools.cached_property
    def text(self) -> Callable[..., str]:
        """``text(value, offset=None)``: rostopic echo's text, without the ``---``."""
        from rostools.msgs.text import formatter

        return formatter(self.codec, self.value_type, self.text_options)

    def texts(self) -> Callable[[list[Any]], list[str]]:
        """Raw messages to echo's text, each ending in ``---``: one compiled call each."""
        from rostools.msgs.text import formatter

        fmt = formatter(self.codec, self.value_type, self.text_options, suffix="\n---\n")
        decode = self.decode
        return lambda frames: [fmt(decode(f, 0)[0]) for f in frames]

    @functools.cached_property
    def plain(self) -> Callable[[Any], Any]:
        """A value as plain data: dicts, lists, numbers and text (YAML, the API)."""
        from rostools.msgs.plain import to_plain

        return to_plain(self.codec, self.value_type)

    @functools.cached_property
    def json(self) -> Callable[[Any], str]:
        """A value as one line of compact JSON."""
        from rostools.msgs.plain import to_json

        return to_json(self.codec, self.value_type)

    def jsons(self) -> Callable[[list[Any]], list[str]]:
        """Raw messages to NDJSON lines: one compiled call each."""
        as_json, decode = self.json, self.decode
        return lambda frames: [as_json(decode(f, 0)[0]) + "\n" for f in frames]

    @functools.cached_property
    def csv_row(self) -> Callable[[Any, int], str]:
        """``csv_row(value, offset)``: rostopic echo -p's row, without the time."""
        from rostools.msgs.plain import csv_row

        return csv_row(self.codec, self.value_type, self.csv_options)

    def csv_header(self, value: Any) -> str:
        """The CSV header for rows like ``value``'s (array lengths are its)."""
        from rostools.msgs.plain import csv_header

        return csv_header(self.codec, self.value_type, value, self.csv_options)

    @staticmethod
    def stamp(value: Any) -> int | None:
        """``header.stamp`` in ns, where the value has one."""
        from rostools.msgs.plain import stamp_ns

        return stamp_ns(value)
