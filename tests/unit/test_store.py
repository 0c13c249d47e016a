"""The type store: sources, precedence, md5sums and full definitions."""

from __future__ import annotations

import hashlib
from pathlib import Path

import pytest

from rostools.errors import NotFoundError
from rostools.msgs.store import BuiltinSource, PathSource, TypeStore


def _package(root: Path, name: str, files: dict[str, str], xml_name: str | None = None) -> Path:
    folder = root / name
    for rel, text in files.items():
        path = folder / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)
    if xml_name is not None:
        (folder / "package.xml").write_text(f"<package><name>{xml_name}</name></package>")
    return folder


@pytest.fixture
def store(tmp_path: Path) -> TypeStore:
    _package(tmp_path / "ws" / "src" / "repo", "pkg_dir", {"msg/Foo.msg": "int32 x\n"}, "my_pkg")
    _package(tmp_path / "ws", "other", {"msg/Bar.msg": "my_pkg/Foo f\n", "srv/Do.srv": "---\n"})
    return TypeStore([PathSource([tmp_path / "ws"]), BuiltinSource()])


def test_packages_found_by_package_xml_name_below_the_root(store: TypeStore) -> None:
    assert store.msg("my_pkg/Foo").fields[0].name == "x"
    assert "my_pkg" in store.packages("msg")
    assert store.types("msg", "other") == ["other/Bar"]
    assert store.types("srv", "other") == ["other/Do"]


def test_md5_of_nested_user_types(store: TypeStore) -> None:
    foo = hashlib.md5(b"int32 x").hexdigest()
    assert store.md5("my_pkg/Foo") == foo
    assert store.md5("other/Bar") == hashlib.md5(f"{foo} f".encode()).hexdigest()


@pytest.mark.parametrize(
    ("line", "md5text"),
    [
        ('string S="hi"', 'string S="hi"'),
        ("float64 X=1e-3", "float64 X=1e-3"),
        ("float64 X=1.50", "float64 X=1.50"),
        ("int32 X=+5", "int32 X=+5"),
        ("string S=", "string S="),
        ("string S= a # b ", "string S=a # b"),
    ],
)
def test_md5_keeps_constant_literals_rosbags_rewrites(
    tmp_path: Path, line: str, md5text: str
) -> None:
    _package(tmp_path, "p", {"msg/C.msg": line + "\nint32 y\n"})
    store = TypeStore([PathSource([tmp_path])])
    expected = hashlib.md5(f"{md5text}\nint32 y".encode()).hexdigest()
    assert store.md5("p/C") == expected


def test_search_path_wins_over_builtin(tmp_path: Path) -> None:
    _package(tmp_path, "std_msgs", {"msg/String.msg": "# mine\nstring data\n"})
    store = TypeStore([PathSource([tmp_path]), BuiltinSource()])
    assert store.msg("std_msgs/String").text == "# mine\nstring data\n"
    assert store.md5("std_msgs/String") == "992ce8a1687cec8c8bd883ec73ca41d1"


def test_builtin_types_and_services() -> None:
    store = TypeStore([BuiltinSource()])
    assert store.md5("geometry_msgs/PoseStamped") == "d3812c3cbc69362b77dc0b19b345f8f5"
    assert store.md5("sensor_msgs/Image") == "060021388200f6f0f447d0fcd9c64743"
    assert store.md5("rosgraph_msgs/Log") == "acffd30cd6b6de30f120938c17c593fb"
    assert store.srv_md5("rospy_tutorials/AddTwoInts") == "6a2e34150c00229791cc89ff309fff21"
    assert store.srv_md5("roscpp/SetLoggerLevel") == "51da076440d78ca1684d36c868df61ea"
    assert store.srv_md5("roscpp/GetLoggers") == "32e97e85527d4678a8f9279894bb64b0"
    assert store.srv_md5("std_srvs/Empty") == "d41d8cd98f00b204e9800998ecf8427e"


def test_full_text_layout() -> None:
    store = TypeStore([BuiltinSource()])
    assert store.full_text("std_msgs/String") == "string data\n"
    full = store.full_text("geometry_msgs/PointStamped")
    assert full.startswith("std_msgs/Header header\ngeometry_msgs/Point point\n\n" + "=" * 80)
    assert "\nMSG: std_msgs/Header\n" in full and full.endswith("float64 z\n")


def test_learnt_definition_is_used_first_and_round_trips() -> None:
    base = TypeStore([BuiltinSource()])
    full = "int32 a # custom\n\n" + "=" * 80 + "\nMSG: std_msgs/Header\nuint32 seq\n"
    learnt = base.with_definition("x/Y", "int32 a # custom\nstd_msgs/Header h\n")
    assert learnt.msg("x/Y").fields[1].base == "std_msgs/Header"
    assert learnt.full_text("x/Y").startswith("int32 a # custom\nstd_msgs/Header h\n")
    assert base.with_definition("x/Z", full).msg("std_msgs/Header").fields[0].name == "seq"
    # An empty definition (seen in real bags) falls back to the store's own types.
    assert base.with_definition("std_msgs/String", "").md5("std_msgs/String") == (
        "992ce8a1687cec8c8bd883ec73ca41d1"
    )


def test_unknown_and_recursive_types(tmp_path: Path) -> None:
    _package(tmp_path, "p", {"msg/A.msg": "p/B b\n", "msg/B.msg": "p/A a\n"})
    store = TypeStore([PathSource([tmp_path])])
    with pytest.raises(NotFoundError, match="unknown message type p/Nope"):
        store.msg("p/Nope")
    with pytest.raises(Exception, match="contains itself"):
        store.md5("p/A")


def test_bare_name_search(store: TypeStore) -> None:
    assert store.find("msg", "Foo") == ["my_pkg/Foo"]
    assert "std_msgs/String" in store.find("msg", "String")
