"""The start-up machinery, tested directly: what keeps Typer and the API off the quick path.

Three pieces (ARCHITECTURE.md, "Start-up time"): a command module imports Typer and its
option aliases under ``if TYPE_CHECKING:`` only, and ``cli/register.py`` reads that block when
a group is built (``_annotation_names``); it ``eval``s each annotation, which stays text under
``from __future__ import annotations`` (``_resolved``); and a package's public names load on
first use from its own ``TYPE_CHECKING`` block (``lazy.homes``, ``lazy.load``).
"""

from __future__ import annotations

import importlib
import sys
import textwrap
from collections.abc import Iterator
from pathlib import Path
from typing import Annotated, get_args, get_origin

import pytest

from rostools import lazy
from rostools.cli import register

COMMANDS = '''
from __future__ import annotations

TYPE_CHECKING = False
if TYPE_CHECKING:
    from fractions import Fraction

    Ratio = Annotated[Fraction | None, "a ratio"]
from typing import Annotated

LIMIT = 3


def run(ratio: Ratio = None, count: Annotated[int, "a count"] = LIMIT) -> None:
    """A command whose annotations name what only its TYPE_CHECKING block imports."""
'''

PACKAGE = '''
"""A package whose public names load on first use."""

from __future__ import annotations

TYPE_CHECKING = False
if TYPE_CHECKING:
    from {name}.heavy import Heavy as Heavy, helper as helper
    from {name}.other import Other as Renamed


def __getattr__(name: str) -> object:
    from rostools import lazy

    return lazy.load(__name__, name)
'''


@pytest.fixture
def modules(tmp_path: Path) -> Iterator[Path]:
    """A folder on ``sys.path`` for modules written by a test, forgotten afterwards."""
    before = set(sys.modules)
    sys.path.insert(0, str(tmp_path))
    try:
        yield tmp_path
    finally:
        sys.path.remove(str(tmp_path))
        for name in set(sys.modules) - before:
            del sys.modules[name]
        register._annotation_names.cache_clear()
        lazy._block.cache_clear()


def write_commands(folder: Path, name: str) -> object:
    (folder / f"{name}.py").write_text(COMMANDS)
    return importlib.import_module(name)


def test_the_type_checking_block_is_read_when_the_group_is_built(modules: Path) -> None:
    module = write_commands(modules, "machinery_cmds")
    assert "Fraction" not in vars(module)  # not imported at run time: the quick path's gain
    names = register._annotation_names("machinery_cmds")
    assert names["Fraction"].__module__ == "fractions"
    assert names["LIMIT"] == 3  # the module's own names stay visible
    assert "Fraction" not in vars(module)  # read into a copy: the module is left as it was


def test_an_annotation_is_evaluated_where_it_was_written(modules: Path) -> None:
    module = write_commands(modules, "machinery_eval")
    written = module.run.__annotations__  # type: ignore[attr-defined]
    assert written["count"] == "Annotated[int, 'a count']"  # text, as the future import keeps it
    count = register._resolved(written["count"], "machinery_eval")
    assert get_origin(count) is Annotated and get_args(count) == (int, "a count")
    ratio = register._resolved(written["ratio"], "machinery_eval")  # NameError, then the block
    kind, help_text = get_args(ratio)
    assert help_text == "a ratio" and set(get_args(kind)) == {
        register._annotation_names("machinery_eval")["Fraction"],
        type(None),
    }
    assert register._resolved(int, "machinery_eval") is int  # an object is left alone


def test_a_none_default_keeps_its_annotated_option(modules: Path) -> None:
    """Not ``get_type_hints``: before 3.11 it would wrap ``ratio`` in ``Optional``."""
    write_commands(modules, "machinery_none")
    ratio = register._resolved("Ratio", "machinery_none")
    assert get_origin(ratio) is Annotated


def test_a_name_no_block_imports_is_an_error(modules: Path) -> None:
    write_commands(modules, "machinery_missing")
    with pytest.raises(NameError):
        register._resolved("Missing", "machinery_missing")


def write_package(folder: Path, name: str) -> object:
    package = folder / name
    package.mkdir()
    (package / "__init__.py").write_text(textwrap.dedent(PACKAGE.format(name=name)))
    (package / "heavy.py").write_text(
        "class Heavy:\n    pass\n\n\ndef helper() -> int:\n    return 1\n"
    )
    (package / "other.py").write_text("class Other:\n    pass\n")
    return importlib.import_module(name)


def test_homes_are_read_from_the_block(modules: Path) -> None:
    write_package(modules, "machinery_pkg")
    assert lazy.homes("machinery_pkg") == {
        "Heavy": "machinery_pkg.heavy",
        "helper": "machinery_pkg.heavy",
        "Renamed": "machinery_pkg.other",
    }
    assert "machinery_pkg.heavy" not in sys.modules  # reading the block imports nothing


def test_a_name_loads_on_first_use_and_stays(modules: Path) -> None:
    package = write_package(modules, "machinery_lazy")
    assert package.__all__ == ["Heavy", "Renamed", "helper"]  # type: ignore[attr-defined]
    assert "machinery_lazy.heavy" not in sys.modules
    heavy = package.Heavy  # type: ignore[attr-defined]
    assert heavy.__module__ == "machinery_lazy.heavy"
    assert vars(package)["Heavy"] is heavy  # kept: the next use is a plain attribute
    assert package.Renamed.__name__ == "Other"  # type: ignore[attr-defined]
    with pytest.raises(AttributeError, match="has no attribute 'Nothing'"):
        package.Nothing  # type: ignore[attr-defined]  # noqa: B018


def test_rostools_api_names_come_from_their_homes() -> None:
    homes = lazy.homes("rostools")
    assert homes["Node"] == "rostools._api.blocking"
    assert homes["AsyncNode"] == "rostools._api.asyncnode"
    for name, home in homes.items():
        assert name in vars(importlib.import_module(home)), f"{home} has no {name}"
