"""Messages as text, byte for byte what ``rostopic echo`` prints (genpy's ``strify_message``).

A formatter is generated per (type, options): the layout of a type is static, so most of a
message becomes one f-string. Strings are quoted as PyYAML's double-quoted style does; the
common case (short printable ASCII) is done inline and PyYAML only handles the rest.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

from rostools.msgs.codec import BYTE_TYPES, STRUCT_CODES, Codec
from rostools.msgs.codegen import GeneratedCode, attr_name, element
from rostools.msgs.message import Time
from rostools.msgs.spec import Field, MsgSpec

# Printable ASCII but '"' and '\\', shorter than 70: PyYAML never folds or escapes these (its
# best_width is 80), so they are quoted as they are, in one regex match.
_PLAIN = re.compile(r"[ !#-\[\]-~]{1,69}").fullmatch


class TextFormatter(Protocol):
    """A generated formatter: ``fmt(value, offset=None) -> str``."""

    def __call__(self, value: Any, offset: Time | None = None) -> str:
        """The text of ``value``."""


@dataclass(frozen=True)
class TextOptions:
    """What ``rostopic echo`` options change in the text.

    ``nostr``/``noarr`` replace strings and arrays by a summary, as rostopic does, and also
    inside arrays of messages, where rostopic forgets to. ``width`` is ``-w``. ``offset``
    prints time fields relative to the time passed with each message (``--offset``).
    """

    nostr: bool = False
    noarr: bool = False
    width: int | None = None
    offset: bool = False


#: Quoted strings by value: frame ids and enum-like strings repeat in every message. Bounded:
#: once full, new strings are quoted each time (a lookup that misses costs little).
_QUOTED: dict[str, str] = {}
QUOTE_CACHE = 4096


def quote(value: str) -> str:
    """A string as genpy prints it: ``''`` when empty, else YAML double-quoted."""
    done = _QUOTED.get(value)
    if done is not None:
        return done
    if _PLAIN(value):
        done = f'"{value}"'
    elif not value:
        done = "''"
    else:
        import yaml

        done = str(yaml.dump(value, default_style='"')).rstrip("\n")
    if len(_QUOTED) < QUOTE_CACHE and len(value) <= 256:
        _QUOTED[value] = done
    return done


def _string_list(values: Sequence[str], indent: str) -> str:
    if not values:
        return "[]"
    import yaml

    dumped = str(yaml.dump(list(values))).rstrip("\n")
    if dumped.startswith("["):
        return dumped
    return "\n" + "\n".join(indent + line for line in dumped.splitlines())


def _num_width(value: Any, width: int) -> str:
    if type(value) is float:
        text = f"%.{width}f" % value
        return text[: max(text.find("."), width)]
    if type(value) is int:
        return f"%{width}d" % value
    return str(value)


def _list(values: Any, width: int | None) -> str:
    if not len(values):
        return "[]"
    items = list(values)
    if width is not None and type(items[0]) in (int, float):
        return "[" + ", ".join(_num_width(v, width) for v in items) + "]"
    return str(items)


def _char_array(values: Any, width: int | None) -> str:
    if isinstance(values, bytes | bytearray):
        return str(bytes(values))  # genpy prints char[] as a bytes repr
    return _list(values, width)


def _time(value: Any, indent: str, width: int | None, offset: Time | None) -> str:
    if offset is not None and isinstance(value, Time):
        value = value - offset
    if width is not None:
        return f"\n{indent}secs: {value.secs:{width}d}\n{indent}nsecs: {value.nsecs:{width}d}"
    return f"\n{indent}secs: {value.secs}\n{indent}nsecs: {value.nsecs:9d}"


def _items(values: Any, prefix: str, item: Callable[[Any, Any], str], offset: Any) -> str:
    if not len(values):
        return "[]"
    return "\n" + "\n".join([prefix + item(v, offset) for v in values])


def _escape(text: str) -> str:
    return (
        text.replace("\\", "\\\\")
        .replace('"', '\\"')
        .replace("\n", "\\n")
        .replace("{", "{{")
        .replace("}", "}}")
    )


class _TextGen(GeneratedCode):
    def __init__(self, codec: Codec, options: TextOptions) -> None:
        super().__init__({
            "_q": quote, "_strs": _string_list, "_nw": _num_width, "_list": _list,
            "_chars": _char_array, "_time": _time, "_items": _items, "_W": options.width,
        })  # fmt: skip
        self.codec = codec
        self.options = options
        self.parts: list[str] = []  # f-string source pieces

    def lit(self, text: str) -> None:
        self.parts.append(_escape(text))

    def expr(self, code: str) -> None:
        self.parts.append("{" + code + "}")

    def body(self, spec: MsgSpec, expr: str, indent: str) -> None:
        if self.codec.inline(spec.name):
            self.fields(spec.fields, expr, indent, first=True)
            return
        # one f-string of 100,000 fields took 40 s and 300 MB to compile: parts, as the codec
        for i, part in enumerate(self.codec.parts(spec)):
            gen = _TextGen(self.codec, self.options)
            gen.fields(part, "m", indent, first=not i)
            fn = gen.formatter(f"{spec.name} part {i}")
            self.expr(f"{self.ref(fn)}({expr}, offset)")

    def fields(self, fields: Sequence[Field], expr: str, indent: str, *, first: bool) -> None:
        for i, f in enumerate(fields):
            self.lit(("" if first and not i else "\n") + f"{indent}{f.name}: ")
            self.value(f, f"{expr}.{attr_name(f.name)}", indent + "  ")

    def value(self, f: Field, expr: str, indent: str) -> None:
        opts = self.options
        if opts.noarr and f.is_array:
            template = self.ref(f"<array type: {f.type.rstrip('[]')}, length: %d>")
            self.expr(f"_q({template} % len({expr}))")
        elif opts.nostr and f.type == "string":
            self.expr(f"_q('<string length: %d>' % len({expr}))")
        elif opts.nostr and f.type == "string[]":
            self.expr(f"_q('<array type: string, length: %d>' % len({expr}))")
        elif f.is_array:
            self.array(f, expr, indent)
        elif f.base == "string":
            self.expr(f"_q({expr})")
        elif f.base in ("time", "duration"):
            if opts.width is None and not opts.offset:
                self.lit(f"\n{indent}secs: ")
                self.expr(f"{expr}.secs")
                self.lit(f"\n{indent}nsecs: ")
                self.expr(f"{expr}.nsecs:9d")
            else:
                self.expr(f"_time({expr}, {self.ref(indent)}, _W, offset)")
        elif f.base in STRUCT_CODES:
            if opts.width is not None and f.base != "bool":
                self.expr(f"_nw({expr}, _W)")
            else:
                self.expr(expr)
        else:
            if indent:
                self.lit("\n")
            self.body(self.codec.store.msg(f.base), expr, indent)

    def array(self, f: Field, expr: str, indent: str) -> None:
        if f.base == "char":
            self.expr(f"_chars({expr}, _W)")
        elif f.base in BYTE_TYPES or f.base in STRUCT_CODES:
            width = "_W" if f.base != "bool" else "None"
            self.expr(f"_list({expr}, {width})")
        elif f.base == "string":
            self.expr(f"_strs({expr}, {self.ref(indent)})")
        else:  # time, duration and messages: one "- " item per element
            item = formatter(self.codec, element(f.base), self.options, indent + "  ")
            self.expr(f"_items({expr}, {self.ref(indent + '- ')}, {self.ref(item)}, offset)")

    def formatter(self, name: str) -> TextFormatter:
        self.line('return f"' + "".join(self.parts) + '"')
        fn: TextFormatter = self.compile("fmt(m, offset=None)", "text", name)
        return fn


def formatter(
    codec: Codec,
    value_type: Field,
    options: TextOptions = TextOptions(),
    indent: str = "",
    suffix: str = "",
) -> TextFormatter:
    """``fmt(value, offset=None) -> str`` for values of ``value_type`` at ``indent``.

    ``value_type`` describes a message (``Field('', 'pkg/T', 'pkg/T', False, None)``), a
    field, or an array of either (what a field path with a slice yields). ``suffix`` is
    added inside the generated f-string (echo's ``---`` line), which is cheaper than after.
    """
    key = ("text", value_type.type, value_type.is_array, options, indent, suffix)
    fn = codec.store.cache.get(key)
    if fn is None:
        gen = _TextGen(codec, options)
        gen.value(value_type, "m", indent)
        gen.lit(suffix)
        fn = codec.store.cache[key] = gen.formatter(value_type.type)
    return fn


def message_type(name: str) -> Field:
    """The value type of a whole message of type ``name``."""
    return Field("", name, name, False, None)
