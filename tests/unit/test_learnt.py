"""The decoder cache: one codec per (type, md5sum, definition), shared by every path.

Wire bytes are written by hand from the ROS 1 serialisation rules (little-endian, a uint32
length before a string); md5sums are genmsg's.
"""

from __future__ import annotations

import struct
from collections.abc import Iterator

import pytest

from rostools._api import messages
from rostools.cli.output import Format
from rostools.cli.topic.printing import Echo, EchoOptions
from rostools.errors import NotFoundError
from rostools.msgs import learnt
from rostools.msgs.codec import Codec
from rostools.msgs.spec import DefinitionError
from rostools.msgs.store import TypeStore

STRING_MD5 = "992ce8a1687cec8c8bd883ec73ca41d1"  # std_msgs/String, as rosmsg md5 gives it
HI = b"\x02\x00\x00\x00hi"  # std_msgs/String "hi"
POINT_SECTION = "=" * 80 + "\nMSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z"


@pytest.fixture(autouse=True)
def fresh_cache(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """Each test starts with empty tables (the process's are shared by design)."""
    monkeypatch.setattr(learnt, "_shared", {})
    monkeypatch.setattr(messages, "_decoders", {})
    yield


def test_a_hit_reuses_the_codec_and_its_decoder() -> None:
    base = TypeStore.default()
    first = learnt.codec(base, "std_msgs/String", STRING_MD5, "string data\n")
    assert learnt.codec(base, "std_msgs/String", STRING_MD5, "string data\n") is first
    decode = learnt.decoder(base, "std_msgs/String", STRING_MD5, "string data\n")
    assert decode is first.decoder("std_msgs/String")
    assert decode(HI, 0)[0].data == "hi"


def test_another_md5_or_definition_gets_another_decoder() -> None:
    base = TypeStore([])
    as_int = learnt.codec(base, "test_pkg/T", "*", "int32 a")
    assert learnt.codec(base, "test_pkg/T", "0" * 32, "int32 a") is not as_int
    as_float = learnt.codec(base, "test_pkg/T", "*", "float64 a")
    assert as_float is not as_int
    assert as_int.decode("test_pkg/T", struct.pack("<i", -7)).a == -7
    assert as_float.decode("test_pkg/T", struct.pack("<d", 1.5)).a == 1.5


def test_a_whole_definition_is_shared_whatever_the_callers_store() -> None:
    """``bag doctor`` reads over no store, the CLI over the default one: one codec."""
    definition = "geometry_msgs/Point p\n" + POINT_SECTION
    alone = learnt.codec(TypeStore([]), "test_pkg/P", "*", definition)
    assert learnt.codec(TypeStore.default(), "test_pkg/P", "*", definition) is alone
    wire = struct.pack("<3d", 1.0, -2.0, 0.5)
    p = alone.decode("test_pkg/P", wire).p
    assert (p.x, p.y, p.z) == (1.0, -2.0, 0.5)


def test_a_partial_definition_is_completed_from_the_callers_store() -> None:
    """A section left out is read from the store the caller gives, and kept with it."""
    partial = "geometry_msgs/Point p\n"
    wire = struct.pack("<3d", 1.0, 2.0, 3.0)
    default = learnt.codec(TypeStore.default(), "test_pkg/P", "*", partial)
    assert default.decode("test_pkg/P", wire).p.z == 3.0
    bare = learnt.codec(TypeStore([]), "test_pkg/P", "*", partial)
    assert bare is not default
    with pytest.raises(NotFoundError):
        bare.decoder("test_pkg/P")


def test_an_empty_definition_is_the_stores_own_type() -> None:
    base = TypeStore.default()
    assert learnt.codec(base, "std_msgs/String", STRING_MD5, "") is Codec.of(base)
    assert learnt.codec(base, "std_msgs/String", STRING_MD5, " \n") is Codec.of(base)


def test_a_bad_definition_is_refused_and_not_kept() -> None:
    for _ in range(2):
        with pytest.raises(DefinitionError):
            learnt.codec(TypeStore([]), "test_pkg/R", "*", "test_pkg/R r")
    assert not learnt._shared


def test_the_tables_are_bounded(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(learnt, "MAX_LEARNT", 2)
    base = TypeStore([])
    codecs = [learnt.codec(base, "test_pkg/T", "*", f"int32 a{i}") for i in range(3)]
    assert len(learnt._shared) == 2
    assert learnt.codec(base, "test_pkg/T", "*", "int32 a2") is codecs[2]
    assert learnt.codec(base, "test_pkg/T", "*", "int32 a0") is not codecs[0]  # dropped


def test_echo_and_bag_doctor_share_one_codec() -> None:
    opts = EchoOptions("", None, None, False, False, False, False, False, None, Format.text)
    echo = Echo(TypeStore.default(), opts)
    key = ("std_msgs/String", STRING_MD5, "string data\n")
    assert echo.printer(*key, "/chatter").renderer.codec is learnt.codec(TypeStore([]), *key)


def test_the_api_decodes_each_definition_with_its_own_decoder() -> None:
    """It kept one decoder per (type, md5sum): a second definition sent with md5sum ``*``
    was decoded with the first one's layout."""
    as_int = messages.decoder("test_pkg/T", "*", "int32 a")
    as_float = messages.decoder("test_pkg/T", "*", "float64 a")
    assert as_int(struct.pack("<i", 3)).a == 3  # type: ignore[attr-defined]
    assert as_float(struct.pack("<d", 1.5)).a == 1.5  # type: ignore[attr-defined]
