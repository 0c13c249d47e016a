"""Action types: the seven messages generated from an ``.action`` equal genmsg's, md5 and text.

The reference is the Python that genpy generated for Debian's packages, read as text (its
``_md5sum`` and ``_full_text``), so the test needs no ROS Python to import.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from rostools.errors import NotFoundError
from rostools.msgs.action import SUFFIXES, action_name, split_action, split_generated
from rostools.msgs.spec import DefinitionError
from rostools.msgs.store import BuiltinSource, PathSource, TypeStore

DIST = Path("/usr/lib/python3/dist-packages")
SHARE = Path("/usr/share")

# actionlib's test actions (Debian ships only their generated Python): the files as written.
ACTIONLIB = {
    "Test": "int32 goal\n---\nint32 result\n---\nint32 feedback\n",
    "TwoInts": "int64 a\nint64 b\n---\nint64 sum\n---\n",
    "TestRequest": (
        "int32 TERMINATE_SUCCESS = 0\nint32 TERMINATE_ABORTED = 1\nint32 TERMINATE_REJECTED = 2\n"
        "int32 TERMINATE_LOSE = 3\nint32 TERMINATE_DROP = 4\nint32 TERMINATE_EXCEPTION = 5\n"
        "int32 terminate_status\nbool ignore_cancel  # If true, ignores requests to cancel\n"
        "string result_text\nint32 the_result    # Desired value for the_result in the Result\n"
        "bool is_simple_client\n"
        "duration delay_accept  # Delays accepting the goal by this amount of time\n"
        "duration delay_terminate  # Delays terminating for this amount of time\n"
        "duration pause_status  # Pauses the status messages for this amount of time\n"
        "---\nint32 the_result\nbool is_simple_server\n---\n"
    ),
}


def generated(package: str, type_short: str) -> tuple[str, str] | None:
    """(md5sum, full text) from genpy's module for ``package/type_short``, if installed."""
    path = DIST / package / "msg" / f"_{type_short}.py"
    if not path.is_file():
        return None
    values: dict[str, str] = {}
    for node in ast.walk(ast.parse(path.read_text())):
        target = node.targets[0] if isinstance(node, ast.Assign) else None
        if isinstance(target, ast.Name) and target.id in ("_md5sum", "_full_text"):
            values[target.id] = ast.literal_eval(node.value)  # type: ignore[attr-defined]
    return values["_md5sum"], values["_full_text"]


def check_against_genpy(store: TypeStore, package: str, stem: str) -> int:
    """Compare the seven messages; how many genpy modules there were to compare."""
    compared = 0
    for suffix in SUFFIXES:
        reference = generated(package, stem + suffix)
        if reference is None:
            continue
        name = f"{package}/{stem}{suffix}"
        assert store.md5(name) == reference[0], name
        assert store.full_text(name) == reference[1], name
        compared += 1
    return compared


@pytest.mark.skipif(
    not (DIST / "actionlib" / "msg" / "_TestAction.py").is_file(),
    reason="python3-actionlib is not installed (scripts/install-ros1-peers.sh)",
)
@pytest.mark.parametrize("stem", sorted(ACTIONLIB))
def test_actionlib_test_actions_equal_genmsg(tmp_path: Path, stem: str) -> None:
    folder = tmp_path / "actionlib" / "action"
    folder.mkdir(parents=True)
    (folder / f"{stem}.action").write_text(ACTIONLIB[stem])
    # the nested types' texts from their files, as genpy saw them (the table drops comments)
    store = TypeStore([PathSource([tmp_path], shallow=[SHARE]), BuiltinSource()])
    assert check_against_genpy(store, "actionlib", stem) == 7
    spec = store.action(f"actionlib/{stem}Action")
    assert spec.text == ACTIONLIB[stem]


@pytest.mark.parametrize(
    ("package", "stem"), [("nav_msgs", "GetMap"), ("tf2_msgs", "LookupTransform")]
)
def test_installed_action_files_equal_genmsg(package: str, stem: str) -> None:
    action = SHARE / package / "action" / f"{stem}.action"
    if not action.is_file() or generated(package, f"{stem}Action") is None:
        pytest.skip(f"{action} and its generated Python are not installed (ROS 1 peers)")
    store = TypeStore([PathSource([], shallow=[SHARE]), BuiltinSource()])
    assert check_against_genpy(store, package, stem) >= 4
    assert store.action(f"{package}/action/{stem}").text == action.read_text()
    assert f"{package}/{stem}ActionGoal" in store.types("msg", package)


def test_a_file_ending_in_a_newline_gives_a_feedback_ending_in_two() -> None:
    assert split_action("a\n---\nb\n---\nc\n") == ("a\n", "b\n", "c\n\n")
    assert split_action("a\n---\nb\n---\nc") == ("a\n", "b\n", "c\n")
    assert split_action("---  x\n--- y\n") == ("", "", "\n")  # dashes then anything: a split
    with pytest.raises(DefinitionError, match="3 parts"):
        split_action("a\n---\nb\n", "p/Two")


def test_names() -> None:
    assert action_name("p/Fib") == action_name("p/FibAction") == "p/FibAction"
    assert action_name("p/action/Fib") == action_name("p/Fib.action") == "p/FibAction"
    assert split_generated("p/FibActionGoal") == ("p/Fib", "ActionGoal")
    assert split_generated("p/FibGoal") == ("p/Fib", "Goal")
    assert split_generated("p/Goal") is None


def test_store_finds_actions_from_files_and_refuses_partial_ones(tmp_path: Path) -> None:
    (tmp_path / "my_pkg" / "action").mkdir(parents=True)
    (tmp_path / "my_pkg" / "action" / "Fib.action").write_text(
        "int32 order\n---\nint32[] sequence\n---\nint32[] partial\n"
    )
    (tmp_path / "my_pkg" / "msg").mkdir()
    (tmp_path / "my_pkg" / "msg" / "HalfGoal.msg").write_text("int32 x\n")
    store = TypeStore([PathSource([tmp_path]), BuiltinSource()])
    spec = store.action("my_pkg/Fib")
    assert (spec.name, spec.stem) == ("my_pkg/FibAction", "my_pkg/Fib")
    assert [f.name for f in spec.feedback.fields] == ["partial"]
    assert store.msg("my_pkg/FibActionFeedback").fields[2].type == "my_pkg/FibFeedback"
    assert "my_pkg/FibAction" in store.types("msg", "my_pkg")
    assert store.has_action("my_pkg/FibAction") and not store.has_action("my_pkg/Half")
    with pytest.raises(NotFoundError, match="unknown action type my_pkg/HalfAction"):
        store.action("my_pkg/Half")
    # the built-in table carries actionlib's test actions as their seven messages
    builtin = TypeStore([BuiltinSource()]).action("actionlib/Test")
    assert [f.name for f in builtin.goal.fields] == ["goal"]
