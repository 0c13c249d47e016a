"""The code-generation helper the codec, formatters and partial decoders share."""

from __future__ import annotations

import struct

from rostools.msgs import extract, fieldpath, plain, text
from rostools.msgs.codec import Codec
from rostools.msgs.codegen import GeneratedCode, attr_name
from rostools.msgs.store import BuiltinSource, TypeStore


def test_one_name_per_object() -> None:
    gen = GeneratedCode({"_helper": len})
    packer = struct.Struct("<I").unpack_from
    first = gen.ref(packer, "u")
    assert gen.ref(packer, "u") == first
    other = gen.ref(struct.Struct("<I").unpack_from, "u")
    assert other != first
    assert first.startswith("_u") and gen.env[first] is packer
    assert gen.env["_helper"] is len
    assert gen.fresh("n") != gen.fresh("n")


def test_compile_names_the_function_and_its_source() -> None:
    gen = GeneratedCode()
    two = gen.ref(2)
    gen.line(f"return x * {two}")
    fn = gen.compile("double(x)", "test", "pkg/T")
    assert fn(21) == 42
    assert fn.__name__ == "double"
    assert fn.__code__.co_filename == "<rostools test pkg/T>"
    assert two in fn.__globals__ and two not in fn.__code__.co_varnames


def test_bound_refs_are_locals() -> None:
    gen = GeneratedCode()
    two = gen.ref(2)
    gen.line(f"return x * {two}")
    fn = gen.compile("double(x)", "test", "pkg/T", bind=True)
    assert fn(21) == 42
    assert two in fn.__code__.co_varnames


def test_an_empty_body_passes() -> None:
    assert GeneratedCode().compile("nothing(m)", "test", "pkg/T")(1) is None


def test_field_names_that_are_keywords_get_genpys_suffix() -> None:
    """genpy's make_python_safe: a field named ``from`` is the attribute ``from_``."""
    assert attr_name("from") == "from_"
    assert attr_name("data") == "data"


def test_every_generator_compiles_through_the_helper() -> None:
    codec = Codec.of(TypeStore([BuiltinSource()]))
    name = "geometry_msgs/PointStamped"
    value = text.message_type(name)
    path = fieldpath.resolve(codec.store, name, "point/x")
    made = {
        "codec": codec.decoder(name),
        "init": codec.message_class(name).__init__,
        "text": text.formatter(codec, value),
        "plain": plain.to_plain(codec, value),
        "json": plain.to_json(codec, value),
        "csv": plain.csv_row(codec, value, plain.CsvOptions()),
        "extract": extract.extractor(codec, name, path),
    }
    for kind, fn in made.items():
        assert fn.__code__.co_filename.startswith(f"<rostools {kind} "), kind
