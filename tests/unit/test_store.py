"""The type store: sources, precedence, md5sums and full definitions."""

from __future__ import annotations

import hashlib
from pathlib import Path
from typing import Any

import pytest

from rostools.errors import NotFoundError
from rostools.msgs import store as store_module
from rostools.msgs.action import AUTOGEN, SUFFIXES
from rostools.msgs.spec import SECTION_RULE, DefinitionError
from rostools.msgs.store import (
    MAX_NESTING,
    BuiltinSource,
    DefinitionSource,
    PathSource,
    Source,
    TypeStore,
    md5_of,
)


def _package(root: Path, name: str, files: dict[str, str], xml_name: str | None = None) -> Path:
    folder = root / name
    folder.mkdir(parents=True, exist_ok=True)
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


def _sources(monkeypatch: pytest.MonkeyPatch, share: Path, **env: str) -> list[Source]:
    monkeypatch.delenv("ROSTOOLS_MSG_PATH", raising=False)
    monkeypatch.delenv("ROS_PACKAGE_PATH", raising=False)
    for key, value in env.items():
        monkeypatch.setenv(key, value)
    monkeypatch.setattr(store_module, "DEBIAN_SHARE", str(share))
    return TypeStore.default(["cli"]).sources


def test_the_search_path_is_the_options_then_the_environment(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    sources = _sources(monkeypatch, tmp_path, ROSTOOLS_MSG_PATH="a:b", ROS_PACKAGE_PATH="c::d")
    [found, builtin] = sources
    assert isinstance(found, PathSource) and isinstance(builtin, BuiltinSource)
    assert (found.roots, found.shallow) == ([Path(p) for p in ("cli", *"abcd")], [])


def test_without_ros_package_path_debians_share_is_searched_if_it_holds_ros(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    _package(tmp_path, "std_msgs", {}, "std_msgs")  # what Debian's ros-std-msgs installs
    [found, _] = _sources(monkeypatch, tmp_path)
    assert isinstance(found, PathSource) and found.shallow == [tmp_path]
    # rospkg searches only ROS_PACKAGE_PATH when it is set, even empty
    [found, _] = _sources(monkeypatch, tmp_path, ROS_PACKAGE_PATH="")
    assert isinstance(found, PathSource) and (found.roots, found.shallow) == ([Path("cli")], [])
    monkeypatch.setattr(store_module, "DEBIAN_SHARE", str(tmp_path / "nothing"))
    monkeypatch.delenv("ROS_PACKAGE_PATH")
    [only] = TypeStore.default().sources
    assert isinstance(only, BuiltinSource)


def test_the_crawl_follows_rospkg(tmp_path: Path) -> None:
    # a package folder ends the crawl (rospkg does not look inside packages), as do
    # CATKIN_IGNORE, hidden folders and depth; a folder with only srv/ is a package
    _package(tmp_path / "src", "outer", {"sub/inner/msg/In.msg": "int8 i\n"}, "outer")
    _package(tmp_path / "src", "ignored", {"p_ign/msg/I.msg": "int8 i\n", "CATKIN_IGNORE": ""})
    _package(tmp_path / "src" / ".hidden", "p_hid", {"msg/H.msg": "int8 h\n"})
    _package(tmp_path / "a" / "b" / "c", "p_deep", {"msg/D.msg": "int8 d\n"})
    _package(tmp_path / "a" / "b" / "c" / "d", "p_too_deep", {"msg/D.msg": "int8 d\n"})
    _package(tmp_path / "src", "p_srv", {"srv/S.srv": "int8 a\n---\n", "notes.txt": ""})
    store = TypeStore([PathSource([tmp_path])])
    assert store.packages("msg") == ["p_deep"]
    assert store.packages("srv") == ["p_srv"]
    assert store.srv("p_srv/S").request.fields[0].name == "a"
    # a system folder is searched one level deep only
    _package(tmp_path / "sys" / "x", "p_two", {"msg/T.msg": "int8 t\n"})
    shallow = TypeStore([PathSource([], shallow=[tmp_path / "sys", tmp_path / "src"])])
    assert shallow.packages("srv") == ["p_srv"]
    assert shallow.packages("msg") == []


def test_type_files_are_those_with_the_kinds_suffix(tmp_path: Path) -> None:
    files = {"msg/A.msg": "int8 a\n", "msg/README.md": "", "msg/B.msg.orig": "", "msg/C": ""}
    _package(tmp_path, "p", files)
    _package(tmp_path, "acts", {"action/Do.action": "int8 g\n---\n---\n"})
    store = TypeStore([PathSource([tmp_path])])
    assert store.types("msg") == [*(f"acts/Do{s}" for s in sorted(SUFFIXES)), "p/A"]
    assert store.packages("action") == ["acts"]
    assert store.packages("srv") == []


def test_a_type_name_has_one_slash(tmp_path: Path) -> None:
    _package(tmp_path, "a", {"msg/b/C.msg": "int8 c\n", "msg/.msg": "int8 d\n"})
    source = PathSource([tmp_path])
    assert source.text("msg", "a/b/C") is None
    assert source.text("msg", "a/") is None


def test_an_unreadable_definition_says_which_file(tmp_path: Path) -> None:
    folder = _package(tmp_path, "p", {"msg/A.msg": ""})
    (folder / "msg" / "A.msg").write_bytes(b"int8 \xff\n")
    with pytest.raises(DefinitionError, match=r"cannot read .*A\.msg: 'utf-8' codec"):
        TypeStore([PathSource([tmp_path])]).msg("p/A")


def test_a_type_the_path_lacks_comes_from_the_table(store: TypeStore) -> None:
    assert store.md5("std_msgs/String") == "992ce8a1687cec8c8bd883ec73ca41d1"
    assert store.has_msg("std_msgs/String") and not store.has_msg("std_msgs/Nope")
    assert BuiltinSource().packages("action") == []
    assert BuiltinSource().types("action", "nav_msgs") == []


def test_types_learnt_from_a_definition(store: TypeStore) -> None:
    full = f"ab/C c\n{SECTION_RULE}\nMSG: ab/C\nint8 x\n{SECTION_RULE}\nMSG: a/D\nint8 y\n"
    source = DefinitionSource("a/B", full)
    assert source.text("msg", "ab/C") == "int8 x" and source.text("srv", "ab/C") is None
    assert (source.packages("msg"), source.packages("srv")) == (["a", "ab"], [])
    assert (source.types("msg", "a"), source.types("srv", "a")) == (["B", "D"], [])
    learnt = store.with_definition("a/B", full)
    assert learnt.types("msg", "ab") == ["ab/C"]


def test_a_services_halves_are_messages_of_the_store(tmp_path: Path) -> None:
    _package(tmp_path, "p", {"srv/S.srv": "int8 a\n---\nint8 b\n"})
    store = TypeStore([PathSource([tmp_path])])
    assert store.srv("p/S").request.name == "p/SRequest"
    # genmsg's md5 of each half is that of its fields
    assert store.md5("p/SRequest") == hashlib.md5(b"int8 a").hexdigest()
    assert store.md5("p/SResponse") == hashlib.md5(b"int8 b").hexdigest()


def test_unknown_types_say_how_to_find_them(store: TypeStore) -> None:
    cases = [
        (lambda: store.msg("p/Nope"), "unknown message type p/Nope", MSG_PATH_HINT),
        (lambda: store.srv("p/Nope"), "unknown service type p/Nope", MSG_PATH_HINT),
        (lambda: store.msg("Nope"), "unknown message type Nope", "use the form pkg/Type"),
        (lambda: store.srv("Nope"), "unknown service type Nope", "use the form pkg/Type"),
        (lambda: store.action("p/Action"), "unknown action type p/Action", ACTION_FORM),
        (lambda: store.action("p/Nope"), "unknown action type p/NopeAction", ACTION_HINT),
    ]
    for call, message, hint in cases:
        with pytest.raises(NotFoundError) as err:
            call()
        assert (str(err.value), err.value.hint) == (message, hint)


MSG_PATH_HINT = "check the spelling, or add its package folder with --msg-path"
ACTION_FORM = "use the form pkg/NameAction"
ACTION_HINT = "check the spelling, or add the folder of its package (with action/) with --msg-path"

#: What genmsg generated from nav_msgs/GetMap.action (Noetic's ros-nav-msgs, share/msg/).
GENERATED = {
    "GetMapAction": "GetMapActionGoal action_goal\nGetMapActionResult action_result\n"
    "GetMapActionFeedback action_feedback\n",
    "GetMapActionGoal": "Header header\nactionlib_msgs/GoalID goal_id\nGetMapGoal goal\n",
    "GetMapActionResult": "Header header\nactionlib_msgs/GoalStatus status\nGetMapResult result\n",
    "GetMapActionFeedback": "Header header\nactionlib_msgs/GoalStatus status\n"
    "GetMapFeedback feedback\n",
    "GetMapGoal": "# Get the map as a nav_msgs/OccupancyGrid\n",
    "GetMapResult": "nav_msgs/OccupancyGrid map\n",
    "GetMapFeedback": "# no feedback\n",
}


def test_an_action_without_its_file_is_rejoined_from_its_messages(tmp_path: Path) -> None:
    files = {f"msg/{name}.msg": AUTOGEN + ("\n" if "Action" in name else "") + text
             for name, text in GENERATED.items()}  # fmt: skip
    _package(tmp_path, "nav_msgs", files)
    store = TypeStore([PathSource([tmp_path]), BuiltinSource()])
    action = store.action("nav_msgs/GetMap")
    # GetMap.action as Noetic ships it, but for the newline genmsg ends each part with
    assert action.text == (
        "# Get the map as a nav_msgs/OccupancyGrid\n---\nnav_msgs/OccupancyGrid map\n---\n"
        "# no feedback\n"
    )
    assert action.result.name == "nav_msgs/GetMapResult"
    assert store.has_action("nav_msgs/GetMap") and not store.has_action("nav_msgs/Nope")
    # each message on the wire must be there: without the goal's wrapper there is no action
    (tmp_path / "nav_msgs" / "msg" / "GetMapActionGoal.msg").unlink()
    assert not TypeStore([PathSource([tmp_path])]).has_action("nav_msgs/GetMap")


def test_a_type_used_twice_is_no_recursion() -> None:
    # geometry_msgs' PoseStamped and TwistStamped both hold a std_msgs/Header
    definition = "geometry_msgs/PoseStamped p\ngeometry_msgs/TwistStamped t\n"
    assert TypeStore([BuiltinSource()]).with_definition("p/Both", definition).has_msg("p/Both")


@pytest.mark.parametrize(
    ("definition", "said"),
    [
        ("q/Missing m\np/A a\n", "p/A contains itself"),  # checked past an unknown type
        (f"p/B b\n{SECTION_RULE}\nMSG: p/B\np/B again\n", "p/B contains itself"),
    ],
)
def test_recursion_is_found_anywhere(definition: str, said: str) -> None:
    with pytest.raises(DefinitionError, match=f"invalid definition of p/A: {said}"):
        TypeStore([]).with_definition("p/A", definition)


def _chain(levels: int) -> str:
    """A type nesting ``levels`` levels deep in all: p/T0 holds p/T1, ... holds int8."""
    fields = [f"p/T{i + 1} t\n" for i in range(levels - 1)] + ["int8 x\n"]
    return fields[0] + "".join(
        f"{SECTION_RULE}\nMSG: p/T{i}\n{text}" for i, text in enumerate(fields[1:], 1)
    )


def test_nesting_up_to_the_limit_is_allowed() -> None:
    assert TypeStore([]).with_definition("p/T0", _chain(MAX_NESTING)).has_msg("p/T0")
    with pytest.raises(DefinitionError, match="types nest deeper than 64 levels"):
        TypeStore([]).with_definition("p/T0", _chain(MAX_NESTING + 1))


def test_recursion_found_outside_the_check_is_named(tmp_path: Path) -> None:
    _package(tmp_path, "p", {"msg/A.msg": "p/B b\n", "msg/B.msg": "p/A a\n"})
    with pytest.raises(DefinitionError, match=r"^p/A contains itself$"):
        TypeStore([PathSource([tmp_path])]).full_text("p/A")


def test_md5_of_a_definition() -> None:
    assert md5_of("std_msgs/String", "string data\n") == "992ce8a1687cec8c8bd883ec73ca41d1"
    assert md5_of("p/A", "q/Missing m\n") == ""


def test_a_type_shared_at_every_level_is_checked_once(monkeypatch: pytest.MonkeyPatch) -> None:
    # each type holds the next twice: walking every path would be 2**20 visits
    levels = 20
    fields = [f"p/T{i + 1} a\np/T{i + 1} b\n" for i in range(levels - 1)] + ["int8 x\n"]
    definition = fields[0] + "".join(
        f"{SECTION_RULE}\nMSG: p/T{i}\n{text}" for i, text in enumerate(fields[1:], 1)
    )
    looked_up: list[str] = []
    msg = TypeStore.msg

    def counting(self: TypeStore, name: str) -> Any:
        looked_up.append(name)
        return msg(self, name)

    monkeypatch.setattr(TypeStore, "msg", counting)
    assert TypeStore([]).with_definition("p/T0", definition).has_msg("p/T0")
    assert len(looked_up) < 4 * levels
