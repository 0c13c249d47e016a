"""Definitions and bytes from peers and bags that lie: a clean error naming the type, always."""

from __future__ import annotations

import pytest

from rostools.msgs.codec import Codec, DecodeError
from rostools.msgs.spec import SECTION_RULE, DefinitionError
from rostools.msgs.store import TypeStore

BASE = TypeStore.default()


def sections(first: str, *more: tuple[str, str]) -> str:
    return first + "".join(f"{SECTION_RULE}\nMSG: {name}\n{text}" for name, text in more)


DEEP = sections("pkg/T1 t\n", *((f"pkg/T{i}", f"pkg/T{i + 1} t\n") for i in range(1, 3000)))


@pytest.mark.parametrize(
    ("definition", "said"),
    [
        ("pkg/A child\n", "pkg/A contains itself"),
        (sections("pkg/B b\n", ("pkg/B", "pkg/A a\n")), "pkg/A contains itself"),
        (DEEP, "types nest deeper than 64 levels"),  # each of these was a RecursionError
    ],
)
def test_recursive_and_deep_definitions_are_refused(definition: str, said: str) -> None:
    with pytest.raises(DefinitionError, match=f"invalid definition of pkg/.*: {said}"):
        BASE.with_definition("pkg/A" if "T1" not in definition else "pkg/T0", definition)


def test_names_that_clash_with_python_still_build() -> None:
    # the defects: a constant named __slots__ or __qualname__ was a TypeError, and a field
    # named self a SyntaxError in the generated class
    definition = "int32 __slots__=1\nint32 __qualname__=2\nint32 self\ntime Time\nuint8[] bytes\n"
    codec = Codec.of(BASE.with_definition("pkg/K", definition))
    built = codec.message_class("pkg/K")(self=3)
    assert (built.self, built.Time.secs, built.bytes) == (3, 0, b"")
    assert codec.decode("pkg/K", codec.serialize(built)) == built


@pytest.mark.parametrize(
    ("definition", "data"),
    [
        ("string data\n", b""),  # a zero-length frame: was a struct.error
        ("float64[100000000] huge\n", b"\x00" * 16),  # an oversized fixed array: the same
        ("string data\n", b"\xff\xff\xff\x7f"),  # a length that lies
    ],
)
def test_bytes_that_lie_are_a_decode_error(definition: str, data: bytes) -> None:
    codec = Codec.of(BASE.with_definition("pkg/L", definition))
    with pytest.raises(DecodeError, match="cannot decode pkg/L"):
        codec.decode("pkg/L", data)
    with pytest.raises(DecodeError, match="cannot decode pkg/L"):
        codec.message_class("pkg/L").deserialize(data)


@pytest.mark.parametrize("name", ["std_msgs/St\x00r", "a b/C", "pkg/T[3]", "", "/"])
def test_a_type_name_that_is_not_one_is_refused(name: str) -> None:
    """A bag's connection record named its type with a NUL: Python's ``type()`` refused it."""
    with pytest.raises(DefinitionError, match="is not a legal message type name"):
        TypeStore([]).with_definition(name, "int32 a\n")
