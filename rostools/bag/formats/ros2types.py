"""What a ROS 1 type becomes in ROS 2: its name, its ``ros2msg`` schema, its converter.

The rules, in the order they apply:

- ``pkg/Name`` is ``pkg/msg/Name``, unless the renames say otherwise (``RENAMES``, plus the
  user's file: ``tf/tfMessage`` is ``tf2_msgs/msg/TFMessage``);
- a type the target distro ships (rosbags' type store for it) is written as the distro
  defines it; where that differs from the ROS 1 definition, ``ros2cdr``'s rules (rosbags-
  convert's) match the fields: ``std_msgs/Header`` loses ``seq``, a field ROS 2 added gets its
  default, a field it removed is dropped;
- any other type is defined from its ROS 1 definition with the same rules: ``time`` and
  ``duration`` are ``builtin_interfaces/msg/Time`` and ``Duration`` (``sec``/``nanosec``),
  ROS 1's ``byte`` (int8) is ``int8`` and its ``char`` (uint8) is ``uint8`` (ROS 2's ``byte``
  is unsigned and its ``char`` an alias of uint8: the values keep their meaning), constants
  kept;
- a type ROS 2 cannot name (its name must start with a capital letter, and hold letters and
  digits only), a definition that does not parse, or none at all, is ``UnmappableTypeError``,
  naming it: before anything is written.

The user's file (``--types FILE``, YAML) extends the table::

    renames:                      # ROS 1 name: ROS 2 name
      my_pkg/OldName: other_pkg/msg/NewName
    definitions:                  # ROS 2 .msg text of a type the distro does not ship
      other_pkg/msg/NewName: |
        int32 x

rosbags is imported when a mapping is made, not with this module (start-up stays small).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

from rostools.bag.formats.model import BagUsageError, Connection, UnsupportedBagError
from rostools.bag.formats.ros2cdr import ARRAY, BASE, NAME, SEQUENCE, Converters, Desc

#: The ROS 2 distros rosbags ships a type store for, oldest first.
DISTROS: Final = (
    "dashing", "eloquent", "foxy", "galactic", "humble", "iron", "jazzy", "kilted", "lyrical",
)  # fmt: skip
#: The long-term-support ones (May of even years): the default is the newest.
LTS: Final = ("foxy", "humble", "jazzy", "lyrical")
DEFAULT_DISTRO: Final = "lyrical"
#: ROS 1 names ROS 2 ships under another name with the same fields (rosbags-convert's own
#: table). Others that look alike are not renames: rosgraph_msgs/Log and rcl_interfaces/Log
#: number their levels differently, actionlib_msgs and action_msgs differ in fields.
RENAMES: Final[Mapping[str, str]] = {"tf/msg/tfMessage": "tf2_msgs/msg/TFMessage"}
_TIME_TYPES = frozenset(("builtin_interfaces/msg/Time", "builtin_interfaces/msg/Duration"))
#: What ROS 2 accepts as a message name (rosidl: a capital, then letters and digits).
_ROS2_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_]*/msg/[A-Z][A-Za-z0-9]*$")
#: ROS 1 primitives whose ROS 2 namesakes mean something else: written as what they are.
_PRIMITIVES = {"byte": "int8", "char": "uint8"}


class UnmappableTypeError(UnsupportedBagError):
    """A ROS 1 type that has no ROS 2 form (one line naming it)."""


def ros2_name(ros1: str) -> str:
    """``pkg/Name`` as ROS 2 names it, ``pkg/msg/Name`` (a name in that form unchanged)."""
    parts = ros1.split("/")
    return f"{parts[0]}/msg/{parts[-1]}" if len(parts) == 2 else ros1


@dataclass(frozen=True)
class Ros2Type:
    """One ROS 1 connection's type in ROS 2: name, schema, hash and converter.

    ``convert(ros1_bytes) -> bytearray`` gives the CDR of one message (encapsulation header
    first); it raises ``ros2cdr.ConversionError`` on bytes that do not fit the ROS 1 type.
    ``rihs01`` is the type description hash (``RIHS01_...``) Iron and later record.
    ``append`` is the same conversion appending to a buffer (``ros2cdr.Converters.appender``).
    """

    ros1: str
    name: str
    schema: str
    rihs01: str
    convert: Any
    append: Any = None


def load_rules(path: str | Path) -> tuple[dict[str, str], dict[str, str]]:
    """The renames and definitions of a user's types file (``BagUsageError`` if malformed)."""
    import yaml

    try:
        data = yaml.safe_load(Path(path).read_text(encoding="utf-8")) or {}
    except OSError as err:
        raise BagUsageError(f"cannot read the types file {path}: {err.strerror}") from None
    except yaml.YAMLError as err:
        first = str(err).splitlines()[0] if str(err) else "not YAML"
        raise BagUsageError(f"the types file {path} is not YAML: {first}") from None
    if not isinstance(data, dict) or set(data) - {"renames", "definitions"}:
        raise BagUsageError(f"the types file {path} holds 'renames' and 'definitions' maps only")
    out: list[dict[str, str]] = []
    for key in ("renames", "definitions"):
        table = data.get(key) or {}
        if not isinstance(table, dict) or not all(
            isinstance(k, str) and isinstance(v, str) for k, v in table.items()
        ):
            raise BagUsageError(f"the types file {path}: '{key}' maps type names to text")
        out.append(table)
    renames = {ros2_name(k): ros2_name(v) for k, v in out[0].items()}
    definitions = {ros2_name(k): v for k, v in out[1].items()}
    return renames, definitions


class Ros2Mapping:
    """The ROS 2 forms of ROS 1 types, for one target distro (see the module docstring).

    ``map(conn)`` gives a connection's ``Ros2Type`` (cached by type and md5sum) or raises
    ``UnmappableTypeError``. Types it defines are added to its own copy of the distro's store.
    """

    def __init__(self, distro: str = DEFAULT_DISTRO, rules: str | Path | None = None) -> None:
        if distro not in DISTROS:
            raise BagUsageError(
                f"unknown ROS 2 distro {distro!r} (use one of {', '.join(DISTROS)})"
            )
        from rosbags.typesys import Stores, get_typestore

        self.distro = distro
        self.store = get_typestore(Stores[f"ROS2_{distro.upper()}"])
        self.renames = dict(RENAMES)
        definitions: dict[str, str] = {}
        if rules is not None:
            renames, definitions = load_rules(rules)
            self.renames.update(renames)
        self._define(definitions)
        self._src: dict[str, tuple[Any, list[tuple[str, Desc]]]] = {}
        self._by_md5: dict[tuple[str, str], dict[str, Any]] = {}
        self._done: dict[tuple[str, str], Ros2Type] = {}
        self.converters = Converters(self._src_fields, self._dst_fields)

    def _define(self, definitions: Mapping[str, str]) -> None:
        from rosbags.typesys import get_types_from_msg

        types: dict[str, Any] = {}
        for name, text in definitions.items():
            if name in self.store.fielddefs:
                raise BagUsageError(
                    f"{name} ships with ROS 2 {self.distro}: it cannot be redefined"
                )
            try:
                types.update(get_types_from_msg(text, name))
            except Exception as err:  # noqa: BLE001 - rosbags raises several kinds
                raise BagUsageError(
                    f"the definition of {name} does not parse: {_why(err)}"
                ) from None
        self._register(types)

    def _register(self, types: Mapping[str, Any]) -> None:
        new = {k: v for k, v in types.items() if k not in self.store.fielddefs}
        if new:
            self.store.register(new)

    def _src_fields(self, name: str) -> list[tuple[str, Desc]]:
        if name in _TIME_TYPES:
            return list(self.store.fielddefs[name][1])
        return list(self._src[name][1])

    def _dst_fields(self, name: str) -> list[tuple[str, Desc]]:
        return list(self.store.fielddefs[name][1])

    def map(self, conn: Connection) -> Ros2Type:
        """The ROS 2 form of ``conn``'s type (``UnmappableTypeError`` naming it if none)."""
        key = (conn.type, conn.md5sum)
        found = self._done.get(key)
        if found is not None:
            return found
        from rostools.bag.formats.ros2cdr import ReorderedFieldsError

        top = ros2_name(conn.type)
        if not conn.definition.strip():
            conn = _known_definition(conn)
        types = self._parse(conn, top)
        # This connection's ROS 1 types are the ones the converter reads from now on; a
        # type of another md5sum under the same name (an older definition) gets its own.
        self._src.clear()
        self._src.update(types)
        self.converters = Converters(self._src_fields, self._dst_fields)
        dst = self._target(top, types, conn)
        try:
            convert = self.converters.converter(top, dst)
        except ReorderedFieldsError as err:
            raise UnmappableTypeError(f"{conn.type} (on {conn.topic}): {err}") from None
        append = self.converters.appender(top, dst)
        schema, _ = self.store.generate_msgdef(dst, ros_version=2)
        rihs01 = self.store.hash_rihs01(dst)
        result = Ros2Type(conn.type, dst, schema, rihs01, convert, append)
        self._done[key] = result
        return result

    def _parse(self, conn: Connection, top: str) -> dict[str, Any]:
        """The ROS 1 types of ``conn``'s definition, parsed as genmsg does, as rosbags' fields."""
        from rostools.msgs.spec import DefinitionError, parse_msg, split_definition

        types: dict[str, Any] = {}
        name = conn.type
        try:
            for section, text in split_definition(conn.definition, name).items():
                spec = parse_msg(text, section)
                types[ros2_name(spec.name)] = (
                    [(c.name, c.type, c.value) for c in spec.constants],
                    [(f.name, _ros1_desc(f)) for f in spec.fields],
                )
        except DefinitionError as err:
            raise UnmappableTypeError(
                f"{conn.type} (on {conn.topic}): its definition does not parse: {err}"
            ) from None
        for tname, (_, fields) in types.items():
            for fname, desc in fields:
                sub = desc[1][0] if desc[0] in (ARRAY, SEQUENCE) else desc
                if sub[0] == NAME and sub[1] not in types and sub[1] not in _TIME_TYPES:
                    raise UnmappableTypeError(
                        f"{conn.type} (on {conn.topic}): its definition lacks {sub[1]} "
                        f"(field {fname} of {tname})"
                    )
        return types

    def _target(self, top: str, types: Mapping[str, Any], conn: Connection) -> str:
        """The ROS 2 name of ``top``, with every type it needs defined in the store."""
        new: dict[str, Any] = {}

        def target(name: str) -> str:
            if name in _TIME_TYPES:
                return name
            dst = self.renames.get(name, name)
            if dst in self.store.fielddefs or dst in new:
                return dst
            if not _ROS2_NAME.match(dst):
                raise UnmappableTypeError(
                    f"{conn.type} (on {conn.topic}): ROS 2 cannot name the type {dst} "
                    "(a capital first, letters and digits; rename it in a --types file)"
                )
            consts, fields = types[name]
            new[dst] = None  # a placeholder while its fields are mapped
            new[dst] = (
                [(c.upper(), _PRIMITIVES.get(t, t), v) for c, t, v in consts],
                [(f, _desc(d, target)) for f, d in fields],
            )
            return dst

        dst = target(top)
        self._register(new)
        return dst


_EMPTY_MD5 = "d41d8cd98f00b204e9800998ecf8427e"  # of the empty text: a type with no fields


def _known_definition(conn: Connection) -> Connection:
    """``conn`` with the definition of the Noetic type of its name and md5sum, if any.

    Some bags keep only the md5sum; one no Noetic type has is ``UnmappableTypeError``.
    """
    import dataclasses

    from rostools.errors import RostoolsError
    from rostools.msgs.store import TypeStore

    if conn.md5sum == _EMPTY_MD5:
        return conn
    try:
        store = TypeStore.default()
        if store.md5(conn.type) == conn.md5sum:
            return dataclasses.replace(conn, definition=store.full_text(conn.type))
    except RostoolsError:
        pass
    raise UnmappableTypeError(f"{conn.type} (on {conn.topic}): the bag has no definition of it")


def _ros1_desc(f: Any) -> Desc:
    """A ROS 1 field (``msgs.spec.Field``) as rosbags describes fields (its ``Nodetype``)."""
    from rosbags.interfaces import Nodetype

    if f.base in ("time", "duration"):
        one: Desc = (Nodetype.NAME, f"builtin_interfaces/msg/{f.base.capitalize()}")
    elif "/" in f.base:
        one = (Nodetype.NAME, ros2_name(f.base))
    else:
        one = (Nodetype.BASE, (f.base, 0))
    if not f.is_array:
        return one
    if f.length is None:
        return (Nodetype.SEQUENCE, (one, 0))
    return (Nodetype.ARRAY, (one, f.length))


def _desc(desc: Desc, target: Any) -> Desc:
    """A ROS 1 field description in ROS 2 terms: nested names mapped, byte and char."""
    if desc[0] == BASE:
        return (desc[0], (_PRIMITIVES.get(desc[1][0], desc[1][0]), desc[1][1]))
    if desc[0] == NAME:
        return (desc[0], target(desc[1]))
    return (desc[0], (_desc(desc[1][0], target), desc[1][1]))


def _why(err: BaseException) -> str:
    return (str(err).strip().splitlines() or [type(err).__name__])[0]
