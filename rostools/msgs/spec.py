"""Message and service specifications, parsed from ``.msg``/``.srv`` text exactly as genmsg does.

The parser follows genmsg's rules to the letter, quirks included (fields split on single
spaces, string constants that keep ``#``, ``int()``/``float()``/``literal_eval`` constant
values), because the md5sum is computed from what it produces and must equal genmsg's.
"""

from __future__ import annotations

import re
from typing import NamedTuple

from rostools.errors import InvalidDataError

PRIMITIVE_TYPES = frozenset(
    (
        "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64",
        "float32", "float64", "string", "bool", "char", "byte",
    )
)  # fmt: skip
BUILTIN_TYPES = PRIMITIVE_TYPES | {"time", "duration"}
HEADER = "std_msgs/Header"
#: The line between sections of a full message definition (genmsg's ``compute_full_text``).
SECTION_RULE = "=" * 80

_INT_BITS = {
    "int8": 8, "uint8": 8, "byte": 8, "char": 8, "int16": 16, "uint16": 16,
    "int32": 32, "uint32": 32, "int64": 64, "uint64": 64,
}  # fmt: skip
_RESOURCE_RE = re.compile(r"^[A-Za-z][\w/]*$")
_BASE_NAME_RE = re.compile(r"^[A-Za-z]\w*$")
# Other writers use rules of other lengths; genmsg always writes 80.
_SECTION_SPLIT = re.compile(r"\n={3,}\n(?=MSG:)")


class DefinitionError(InvalidDataError):
    """A ``.msg``/``.srv`` text or a message definition that cannot be parsed."""


class Field(NamedTuple):
    """One field of a message.

    ``type`` is the type as genmsg records it: builtins as written (``uint8[16]``, ``byte``),
    message types resolved to ``pkg/Type`` with their array suffix (``geometry_msgs/Point[]``).
    """

    name: str
    type: str
    base: str
    is_array: bool
    length: int | None

    @property
    def is_builtin(self) -> bool:
        """True for primitives, ``time`` and ``duration``."""
        return self.base in BUILTIN_TYPES


class Constant(NamedTuple):
    """A constant declaration; ``text`` is the value as written, which the md5 uses."""

    type: str
    name: str
    value: bool | int | float | str
    text: str


class MsgSpec:
    """A parsed message type."""

    __slots__ = ("constants", "dependencies", "fields", "name", "text")

    def __init__(
        self, name: str, fields: tuple[Field, ...], constants: tuple[Constant, ...], text: str
    ) -> None:
        self.name = name
        self.fields = fields
        self.constants = constants
        self.text = text
        #: Nested message types of the fields, in field order, repeats included.
        self.dependencies = tuple(f.base for f in fields if not f.is_builtin)

    @property
    def package(self) -> str:
        """The package part of the name."""
        return self.name.partition("/")[0]

    @property
    def has_header(self) -> bool:
        """True when the first field is ``Header header`` (ROS rewrites its ``seq``)."""
        return (
            bool(self.fields) and self.fields[0].base == HEADER and self.fields[0].name == "header"
        )

    def __repr__(self) -> str:
        return f"MsgSpec({self.name!r})"


class SrvSpec:
    """A parsed service type: its request and response messages and the ``.srv`` text."""

    __slots__ = ("name", "request", "response", "text")

    def __init__(self, name: str, request: MsgSpec, response: MsgSpec, text: str) -> None:
        self.name = name
        self.request = request
        self.response = response
        self.text = text

    def __repr__(self) -> str:
        return f"SrvSpec({self.name!r})"


def split_type(type_name: str) -> tuple[str, bool, int | None]:
    """Split ``T``, ``T[]`` or ``T[N]`` into (base, is_array, fixed length or None)."""
    bracket = type_name.find("[")
    if bracket < 0:
        return type_name, False, None
    base, suffix = type_name[:bracket], type_name[bracket + 1 : -1]
    return base, True, int(suffix) if suffix else None


def is_valid_type(type_name: str) -> bool:
    """Genmsg's ``is_valid_msg_type``: a resource name with at most one ``[N]`` suffix."""
    if not type_name or type_name != type_name.strip():
        return False
    base = type_name.split("[", 1)[0]
    if not _RESOURCE_RE.match(base) or "//" in base:
        return False
    rest = type_name[len(base) :]
    if not rest:
        return True
    # genmsg accepts several bracket pairs; no ROS tool can serialise them, so we refuse.
    return re.fullmatch(r"\[\d*\]", rest) is not None


def resolve_type(type_name: str, package: str) -> str:
    """Resolve a field type written in ``package`` the way genmsg's loader does."""
    if "/" in type_name:
        return type_name
    if type_name == "Header":
        return HEADER
    base = type_name.split("[", 1)[0]
    if base in BUILTIN_TYPES or not package:
        return type_name
    return f"{package}/{type_name}"


def _strip_comment(line: str) -> str:
    return line.split("#", 1)[0].strip()


def _words(line: str) -> list[str]:
    # genmsg splits on single spaces only: a tab between type and name is an error there too.
    return [w for w in (x.strip() for x in line.split(" ")) if w]


def _constant_value(type_name: str, text: str) -> bool | int | float | str:
    if type_name in ("float32", "float64"):
        return float(text)
    if type_name == "string":
        return text.strip()
    if type_name == "bool":
        import ast  # genmsg evaluates bool constants as Python literals

        return bool(ast.literal_eval(text))
    bits = _INT_BITS[type_name]
    if type_name.startswith("u") or type_name == "char":
        lower, upper = 0, (1 << bits) - 1
    else:
        lower, upper = -(1 << (bits - 1)), (1 << (bits - 1)) - 1
    value = int(text)
    if not lower <= value <= upper:
        raise ValueError(f"cannot coerce [{value}] to {type_name} (out of bounds)")
    return value


def _parse_constant(line: str) -> Constant:
    words = _words(_strip_comment(line))
    type_name = words[0]
    if type_name not in PRIMITIVE_TYPES:
        raise ValueError(f"{type_name} is not a legal constant type")
    if type_name == "string":
        # Everything right of '=' is the value, '#' included (genmsg).
        eq = line.find("=")
        name = line[line.find(" ") + 1 : eq].strip()
        raw = line[eq + 1 :]
    else:
        parts = [x.strip() for x in " ".join(words[1:]).split("=")]
        if len(parts) != 2:
            raise ValueError(f"invalid constant declaration: {line.strip()}")
        name, raw = parts
    try:
        value = _constant_value(type_name, raw)
    except (ValueError, SyntaxError) as err:
        raise ValueError(f"invalid constant value: {err}") from err
    return Constant(type_name, name, value, raw.strip())


def _parse_field(line: str, package: str) -> Field:
    words = _words(_strip_comment(line))
    if len(words) != 2:
        raise ValueError(f"invalid declaration: {line.strip()}")
    type_name, name = words
    if not _BASE_NAME_RE.match(name):
        raise ValueError(f"{name} is not a legal message field name")
    if not is_valid_type(type_name):
        raise ValueError(f"{type_name} is not a legal message field type")
    resolved = resolve_type(type_name, package)
    base, is_array, length = split_type(resolved)
    if base.count("/") > 1:
        raise ValueError(f"{type_name} is not a legal message field type")
    return Field(name, resolved, base, is_array, length)


def parse_msg(text: str, name: str) -> MsgSpec:
    """Parse the text of a ``.msg`` file for the type ``name`` (``pkg/Type``)."""
    package = name.partition("/")[0]
    fields: list[Field] = []
    constants: list[Constant] = []
    for lineno, line in enumerate(text.split("\n"), 1):
        clean = _strip_comment(line)
        if not clean:
            continue
        try:
            if "=" in clean:
                constants.append(_parse_constant(line))
            else:
                fields.append(_parse_field(line, package))
        except (ValueError, IndexError) as err:
            raise DefinitionError(f"{name}: line {lineno}: {err}") from err
    names = [f.name for f in fields]
    if len(set(names)) != len(names):
        dup = next(n for n in names if names.count(n) > 1)
        raise DefinitionError(f"{name}: duplicate field name {dup!r}")
    return MsgSpec(name, tuple(fields), tuple(constants), text)


def parse_srv(text: str, name: str) -> SrvSpec:
    """Parse the text of a ``.srv`` file: request and response split on a ``---`` line."""
    halves: list[list[str]] = [[], []]
    current = 0
    for line in text.split("\n"):
        if line.startswith("---"):  # genmsg is lenient: anything after the dashes is ignored
            current = 1
        else:
            halves[current].append(line + "\n")
    request = parse_msg("".join(halves[0]), f"{name}Request")
    response = parse_msg("".join(halves[1]), f"{name}Response")
    return SrvSpec(name, request, response, text)


def split_definition(full_text: str, name: str) -> dict[str, str]:
    """Split a full ``message_definition`` into the text of each type, top-level first.

    The inverse of genmsg's ``compute_full_text``: re-joining the sections with the same
    rules reproduces the input byte for byte.
    """
    chunks = _SECTION_SPLIT.split(full_text)
    sections = {name: chunks[0]}
    for chunk in chunks[1:]:
        header, _, body = chunk.partition("\n")
        sections.setdefault(header[len("MSG:") :].strip(), body)
    return sections


def normalize_type_name(name: str) -> str:
    """Accept ``pkg/msg/T``, ``pkg/srv/T`` and ``pkg/T``; return ``pkg/T``."""
    parts = name.strip("/").split("/")
    if len(parts) == 3 and parts[1] in ("msg", "srv"):
        return f"{parts[0]}/{parts[2]}"
    return name
