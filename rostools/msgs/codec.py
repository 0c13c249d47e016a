"""Message classes with generated ROS 1 (de)serialisers.

For each type we generate Python source: fixed-size runs of primitives, through nested
messages, are read or written with one ``struct`` call, and nested messages are inlined. This
is what makes ``echo`` of small high-rate topics fast (genpy does the same; rosbags' serde is
2-3x slower for small messages; benchmarks/bench_msg.py).
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Sequence
from typing import Any

from rostools.errors import InvalidDataError
from rostools.msgs.codegen import GeneratedCode, attr_name, element
from rostools.msgs.message import Duration, Message, Time
from rostools.msgs.spec import Field, MsgSpec
from rostools.msgs.store import TypeStore

STRUCT_CODES = {
    "bool": "?", "int8": "b", "byte": "b", "uint8": "B", "char": "B",
    "int16": "h", "uint16": "H", "int32": "i", "uint32": "I",
    "int64": "q", "uint64": "Q", "float32": "f", "float64": "d",
}  # fmt: skip
BYTE_TYPES = frozenset(("uint8", "char"))  # arrays of these are ``bytes`` in Python, as in genpy
# A peer's count of zero-size elements (std_msgs/Empty[]) is not bounded by the buffer.
_MAX_EMPTY_ELEMENTS = 1 << 20
#: The most fields one generated function reads or writes, nested messages' fields counted.
#: Compiling a function costs a few KB per statement until it is done: a type of 100,000
#: fields in one function took 700 MB to compile. A bigger type is done in parts of this
#: many fields, each a function of its own, and a bigger nested type by its own function.
PART_FIELDS = 1000

_U32 = struct.Struct("<I")


class DecodeError(InvalidDataError):
    """Bytes that do not decode as the expected type."""


class EncodeError(InvalidDataError):
    """A message whose field values cannot be serialised."""


#: What a generated decoder can raise on bytes that lie about their type, besides
#: ``DecodeError``: callers of a raw decoder turn these into one.
DECODE_ERRORS = (struct.error, IndexError, ValueError, OverflowError, MemoryError)


#: What the bytes were, for the errors a generated decoder can raise: Python's own texts
#: ("unpack_from requires a buffer of at least 1 bytes") reached peers and users.
SHORT = "message is shorter than its type says"


def _short() -> None:
    raise DecodeError(SHORT)


def why_not(err: BaseException) -> str:
    """What is wrong with bytes a generated decoder raised ``err`` on, in one line of words."""
    if isinstance(err, DecodeError):
        return str(err)
    if isinstance(err, struct.error | IndexError):
        return SHORT
    if isinstance(err, OverflowError | MemoryError):
        return "a length in it is too large"
    return "its bytes do not fit its type"


class _Gen(GeneratedCode):
    """A codec generator: the source of one function, and the codec it asks for nested types."""

    def __init__(self, codec: Codec) -> None:
        super().__init__()
        self.codec = codec


class _DecodeGen(_Gen):
    def __init__(self, codec: Codec) -> None:
        super().__init__(codec)
        self.env["_new"] = object.__new__
        self.pending: list[tuple[str, str]] = []  # (struct code or 'Nx', assignment target)

    def flush(self) -> None:
        if not self.pending:
            return
        fmt = "<" + "".join(code for code, _ in self.pending)
        packer = struct.Struct(fmt)
        ref = self.ref(packer.unpack_from, "u")
        if all(len(code) == 1 for code, _ in self.pending):
            targets = ", ".join(t for _, t in self.pending)
            self.line(f"{targets}, = {ref}(buf, pos)")
        else:  # a fixed array in the run: unpack to a tuple and slice it
            tmp = self.fresh("v")
            self.line(f"{tmp} = {ref}(buf, pos)")
            i = 0
            for code, target in self.pending:
                if len(code) == 1:
                    self.line(f"{target} = {tmp}[{i}]")
                    i += 1
                else:
                    n = int(code[:-1])
                    self.line(f"{target} = {tmp}[{i}:{i + n}]")
                    i += n
        self.line(f"pos += {packer.size}")
        self.pending = []

    def read_count(self) -> str:
        self.flush()
        n = self.fresh("n")
        self.line(f"{n}, = {self.ref(_U32.unpack_from, 'u')}(buf, pos)")
        self.line("pos += 4")
        return n

    def read_bytes(self, target: str, count: str) -> None:
        short = self.ref(_short, "f")
        self.line(f"if pos + {count} > len(buf): {short}()")
        self.line(f"{target} = bytes(buf[pos:pos + {count}])")
        self.line(f"pos += {count}")

    def read_string(self, target: str) -> None:
        n = self.read_count()
        short = self.ref(_short, "f")
        self.line(f"if pos + {n} > len(buf): {short}()")
        self.line(f"{target} = str(buf[pos:pos + {n}], 'utf-8', 'replace')")
        self.line(f"pos += {n}")

    def time(self, base: str, target: str) -> None:
        var = self.fresh("t")
        cls = Time if base == "time" else Duration
        self.line(f"{var} = _new({self.ref(cls, 'C')})")
        self.line(f"{target} = {var}")
        code = "I" if base == "time" else "i"
        self.pending += [(code, f"{var}.secs"), (code, f"{var}.nsecs")]

    def message(self, spec: MsgSpec, target: str | None) -> str:
        var = self.fresh("o")
        self.line(f"{var} = _new({self.ref(self.codec.message_class(spec.name), 'C')})")
        if target:
            self.line(f"{target} = {var}")
        if self.codec.inline(spec.name):
            self.fields(spec.fields, var)
            return var
        for number, part in enumerate(self.codec.parts(spec)):
            self.flush()
            gen = _DecodeGen(self.codec)
            gen.fields(part, "o")
            gen.flush()
            gen.line("return pos")
            what = f"{spec.name} part {number}"
            read = gen.compile("part(buf, pos, o)", "codec", what, bind=True)
            self.line(f"pos = {self.ref(read, 'd')}(buf, pos, {var})")
        return var

    def fields(self, fields: Sequence[Field], var: str) -> None:
        for f in fields:
            self.field(f, f"{var}.{attr_name(f.name)}")

    def field(self, f: Field, target: str) -> None:
        if not f.is_array:
            if f.base == "string":
                self.flush()
                self.read_string(target)
            elif f.base in ("time", "duration"):
                self.time(f.base, target)
            elif f.base in STRUCT_CODES:
                self.pending.append((STRUCT_CODES[f.base], target))
            elif not self.codec.inline(f.base):
                self.flush()
                self.line(f"{target}, pos = {self.ref(self.codec.decoder(f.base), 'd')}(buf, pos)")
            else:
                self.message(self.codec.store.msg(f.base), target)
            return
        if f.base in BYTE_TYPES:
            count = self.read_count() if f.length is None else str(f.length)
            self.flush()
            self.read_bytes(target, count)
        elif f.base in STRUCT_CODES:
            code = STRUCT_CODES[f.base]
            if f.length is not None:
                self.pending.append((f"{f.length}{code}", target))
            else:
                n = self.read_count()
                size = struct.calcsize(code)
                short = self.ref(_short, "f")
                unpack = self.ref(struct.unpack_from, "u")
                self.line(f"if pos + {n} * {size} > len(buf): {short}()")
                self.line(f"{target} = {unpack}('<%d{code}' % {n}, buf, pos)")
                self.line(f"pos += {n} * {size}")
        else:
            count = self.read_count() if f.length is None else str(f.length)
            self.flush()
            one = element(f.base)
            self.check_count(count, f.base)
            items = self.fresh("a")
            self.line(f"{items} = []")
            self.line(f"for _ in range({count}):")
            self.indent += "    "
            if f.base in ("string", "time", "duration"):
                item = self.fresh("e")
                self.field(one, item)
                self.flush()
                self.line(f"{items}.append({item})")
            else:
                decode = self.ref(self.codec.decoder(f.base), "d")
                item = self.fresh("e")
                self.line(f"{item}, pos = {decode}(buf, pos)")
                self.line(f"{items}.append({item})")
            self.indent = self.indent[:-4]
            self.line(f"{target} = {items}")

    def check_count(self, count: str, base: str) -> None:
        if count.isdigit():
            return
        size = self.codec.min_size(base)
        short = self.ref(_short, "f")
        if size:
            self.line(f"if {count} * {size} > len(buf) - pos: {short}()")
        else:
            self.line(f"if {count} > {_MAX_EMPTY_ELEMENTS}: {short}()")


class _EncodeGen(_Gen):
    def __init__(self, codec: Codec) -> None:
        super().__init__(codec)
        self.pending: list[tuple[str, str]] = []  # (struct code, value expression)

    def flush(self) -> None:
        if not self.pending:
            return
        codes = "".join(code for code, _ in self.pending)
        packer = struct.Struct("<" + codes)
        values = ", ".join(v if len(c) == 1 else f"*{v}" for c, v in self.pending)
        self.line(f"w({self.ref(packer.pack, 'p')}({values}))")
        self.pending = []

    def write_count(self, expr: str) -> None:
        self.pending.append(("I", f"len({expr})"))

    def message(self, spec: MsgSpec, expr: str) -> None:
        var = self.fresh("m")
        self.line(f"{var} = {expr}")
        if self.codec.inline(spec.name):
            self.fields(spec.fields, var)
            return
        for number, part in enumerate(self.codec.parts(spec)):
            self.flush()
            gen = _EncodeGen(self.codec)
            gen.fields(part, "m")
            gen.flush()
            write = gen.compile("part(m, w)", "codec", f"{spec.name} part {number}", bind=True)
            self.line(f"{self.ref(write, 'e')}({var}, w)")

    def fields(self, fields: Sequence[Field], var: str) -> None:
        for f in fields:
            self.field(f, f"{var}.{attr_name(f.name)}")

    def field(self, f: Field, expr: str) -> None:
        if not f.is_array:
            if f.base == "string":
                var = self.fresh("s")
                self.line(f"{var} = {expr}")
                self.line(f"{var} = {var}.encode() if {var}.__class__ is str else {var}")
                self.write_count(var)
                self.flush()
                self.line(f"w({var})")
            elif f.base in ("time", "duration"):
                var = self.fresh("t")
                self.line(f"{var} = {expr}")
                code = "I" if f.base == "time" else "i"
                self.pending += [(code, f"{var}.secs"), (code, f"{var}.nsecs")]
            elif f.base in STRUCT_CODES:
                self.pending.append((STRUCT_CODES[f.base], expr))
            elif not self.codec.inline(f.base):
                self.flush()
                self.line(f"{self.ref(self.codec.encoder(f.base), 'e')}({expr}, w)")
            else:
                self.message(self.codec.store.msg(f.base), expr)
            return
        var = self.fresh("a")
        self.line(f"{var} = {expr}")
        if f.length is not None:
            check = self.ref(_check_length, "f")
            self.line(f"{check}({var}, {f.length}, {f.name!r})")
        else:
            self.write_count(var)
        if f.base in BYTE_TYPES:
            self.flush()
            to_bytes = self.ref(_as_bytes, "f")
            self.line(f"w({to_bytes}({var}))")
        elif f.base in STRUCT_CODES:
            self.flush()
            pack = self.ref(struct.pack, "p")
            self.line(f"w({pack}('<%d{STRUCT_CODES[f.base]}' % len({var}), *{var}))")
        else:
            self.flush()
            item = self.fresh("e")
            self.line(f"for {item} in {var}:")
            self.indent += "    "
            if f.base in ("string", "time", "duration"):
                self.field(element(f.base), item)
                self.flush()
            else:
                encode = self.ref(self.codec.encoder(f.base), "e")
                self.line(f"{encode}({item}, w)")
            self.indent = self.indent[:-4]


def _check_length(value: Any, length: int, name: str) -> None:
    if len(value) != length:
        raise EncodeError(f"field {name}: expected {length} elements, got {len(value)}")


def _as_bytes(value: Any) -> bytes:
    # bytes() takes bytes-likes as they are and checks a list of ints for 0..255.
    return value if value.__class__ is bytes else bytes(value)


class Codec:
    """Message classes, decoders and encoders for the types of one ``TypeStore``."""

    def __init__(self, store: TypeStore) -> None:
        self.store = store
        self._classes: dict[str, type[Message]] = {}
        self._decoders: dict[str, Callable[[Any, int], tuple[Any, int]]] = {}
        self._encoders: dict[str, Callable[[Any, Callable[[Any], Any]], None]] = {}
        self._sizes: dict[str, int] = {}
        self._weights: dict[str, int] = {}
        #: ``PART_FIELDS`` for this codec's functions (a test makes it small).
        self.part_fields = PART_FIELDS

    @classmethod
    def of(cls, store: TypeStore) -> Codec:
        """The codec belonging to a store (one per store)."""
        codec = store.cache.get("codec")
        if codec is None:
            codec = store.cache["codec"] = cls(store)
        assert isinstance(codec, Codec)
        return codec

    def min_size(self, name: str) -> int:
        """The fewest bytes a value of type ``name`` can take on the wire."""
        if name in ("string", "time", "duration"):
            return 4 if name == "string" else 8
        size = self._sizes.get(name)
        if size is None:
            size = 0
            for f in self.store.msg(name).fields:
                if (f.is_array and f.length is None) or f.base == "string":
                    size += 4
                elif f.base in ("time", "duration"):
                    size += 8 * (f.length or 1)
                elif f.base in STRUCT_CODES:
                    size += struct.calcsize(STRUCT_CODES[f.base]) * (f.length or 1)
                else:
                    size += self.min_size(f.base) * (f.length or 1)
            self._sizes[name] = size
        return size

    def inline(self, name: str) -> bool:
        """Whether one generated function does all of type ``name`` (else it is in parts)."""
        return self.weight(name) <= self.part_fields

    def weight(self, name: str) -> int:
        """How many fields a function that inlines type ``name`` reads or writes.

        A scalar, string, time or array field is one; a nested message is its own weight,
        or one where that is over ``part_fields`` (then its own function does it).
        """
        weight = self._weights.get(name)
        if weight is None:
            weight = self._weights[name] = sum(map(self._cost, self.store.msg(name).fields))
        return weight

    def _cost(self, f: Field) -> int:
        if f.is_array or f.is_builtin:
            return 1
        inner = self.weight(f.base)
        return inner if inner <= self.part_fields else 1

    def parts(self, spec: MsgSpec) -> list[list[Field]]:
        """The fields of ``spec`` in runs that weigh at most ``part_fields`` each."""
        parts: list[list[Field]] = [[]]
        load = 0
        for f in spec.fields:
            cost = self._cost(f)
            if load + cost > self.part_fields and parts[-1]:
                parts.append([])
                load = 0
            parts[-1].append(f)
            load += cost
        return parts

    def decoder(self, name: str) -> Callable[[Any, int], tuple[Any, int]]:
        """``decode(buf, pos) -> (message, new_pos)`` for type ``name``."""
        fn = self._decoders.get(name)
        if fn is None:
            spec = self.store.msg(name)
            gen = _DecodeGen(self)
            root = gen.message(spec, None)
            gen.flush()
            gen.line(f"return {root}, pos")
            fn = self._decoders[name] = gen.compile("decode(buf, pos)", "codec", name, bind=True)
        return fn

    def encoder(self, name: str) -> Callable[[Any, Callable[[Any], Any]], None]:
        """``encode(message, write)``: calls ``write`` with the pieces of the wire bytes."""
        fn = self._encoders.get(name)
        if fn is None:
            gen = _EncodeGen(self)
            gen.message(self.store.msg(name), "msg")
            gen.flush()
            fn = self._encoders[name] = gen.compile("encode(msg, w)", "codec", name, bind=True)
        return fn

    def message_class(self, name: str) -> type[Message]:
        """The generated class for message type ``name``."""
        cls = self._classes.get(name)
        if cls is None:
            cls = self._classes[name] = self._build_class(self.store.msg(name))
        return cls

    def _default(self, f: Field) -> str:
        """Source of an expression for the default value of a field."""
        if f.is_array:
            if f.base in BYTE_TYPES:
                return f"_bytes({f.length or 0})"
            if f.length is None:
                return "[]"
            one = self._default(element(f.base))
            return f"[{one} for _ in _range({f.length})]"
        if f.base == "string":
            return "''"
        if f.base == "bool":
            return "False"
        if f.base in ("float32", "float64"):
            return "0.0"
        if f.base in STRUCT_CODES:
            return "0"
        if f.base == "time":
            return "_Time()"
        if f.base == "duration":
            return "_Duration()"
        return f"_cls({f.base!r})()"

    def _build_class(self, spec: MsgSpec) -> type[Message]:
        slots = tuple(attr_name(f.name) for f in spec.fields)
        namespace: dict[str, Any] = {
            "__slots__": slots,
            "_type": spec.name,
            "_fields": tuple(f.name for f in spec.fields),
            "_slot_types": tuple(f.type for f in spec.fields),
            "_has_header": spec.has_header,
            "__module__": "rostools.msgs.generated",
        }
        for c in spec.constants:
            if c.name not in slots and not hasattr(Message, c.name):  # never over machinery
                namespace[c.name] = c.value
        cls: type[Message] = type(spec.name.replace("/", "__"), (Message,), namespace)
        cls.__qualname__ = name = spec.name
        # The generated names start with "_", which no ROS field name can (spec.py).
        env = {
            "_U": _UNSET, "_Time": Time, "_Duration": Duration, "_cls": self.message_class,
            "_bytes": bytes, "_range": range,
        }  # fmt: skip
        if len(slots) > self.part_fields:  # a signature alone of 100,000 names took 150 MB
            setattr(cls, "__init__", self._init_of_many(spec, slots, env))  # noqa: B010
        else:
            init = GeneratedCode(env)
            for a, f in zip(slots, spec.fields, strict=True):
                init.line(f"_self.{a} = {self._default(f)} if {a} is _U else {a}")
            params = "".join(f", {a}=_U" for a in slots)
            setattr(cls, "__init__", init.compile(f"__init__(_self{params})", "init", name))  # noqa: B010
        codec = self

        def deserialize(klass: type[Message], data: Any) -> Any:
            return codec.decode(name, data)

        def serialize(self: Message) -> bytes:
            return codec.serialize(self)

        setattr(cls, "deserialize", classmethod(deserialize))  # noqa: B010 - set after creation
        setattr(cls, "serialize", serialize)  # noqa: B010
        return cls

    def _init_of_many(
        self, spec: MsgSpec, slots: tuple[str, ...], env: dict[str, Any]
    ) -> Callable[..., None]:
        """The ``__init__`` of a type of over ``part_fields`` fields, one loop over them.

        It takes what the generated one takes, and refuses what it refuses, with Python's
        words; each distinct default is one small generated function.
        """
        makers: dict[str, Callable[[], Any]] = {}
        defaults: list[tuple[str, Callable[[], Any]]] = []
        for a, f in zip(slots, spec.fields, strict=True):
            expr = self._default(f)
            make = makers.get(expr)
            if make is None:
                gen = GeneratedCode(env)
                gen.line(f"return {expr}")
                make = makers[expr] = gen.compile("default()", "init", spec.name)
            defaults.append((a, make))
        known = frozenset(slots)

        def __init__(_self: Message, *args: Any, **kwargs: Any) -> None:  # noqa: N807
            if len(args) > len(slots):
                raise TypeError(
                    f"__init__() takes from 1 to {len(slots) + 1} positional arguments "
                    f"but {len(args) + 1} were given"
                )
            given = dict(zip(slots, args, strict=False))
            for key in kwargs:
                if key not in known:
                    raise TypeError(f"__init__() got an unexpected keyword argument {key!r}")
                if key in given:
                    raise TypeError(f"__init__() got multiple values for argument {key!r}")
            given |= kwargs
            for a, make in defaults:
                setattr(_self, a, given[a] if a in given else make())

        return __init__

    def decode(self, name: str, data: Any) -> Any:
        """Decode ``data`` (bytes or memoryview) as type ``name``."""
        try:
            return self.decoder(name)(data, 0)[0]
        except (DecodeError, *DECODE_ERRORS) as err:
            raise DecodeError(f"cannot decode {name}: {why_not(err)}") from err

    def serialize(self, msg: Message) -> bytes:
        """Encode a message of a class from this codec."""
        pieces: list[Any] = []
        try:
            self.encoder(msg._type)(msg, pieces.append)
        except (struct.error, TypeError, AttributeError, ValueError) as err:
            if isinstance(err, EncodeError):
                raise
            raise EncodeError(f"cannot serialize {msg._type}: {err}") from err
        return b"".join(pieces)


class _Unset:
    __slots__ = ()

    def __repr__(self) -> str:
        return "<unset>"


_UNSET = _Unset()
