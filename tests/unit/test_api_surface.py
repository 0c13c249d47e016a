"""The public API: what ``from rostools import ...`` offers, and what importing it costs."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

import rostools
import rostools.testing

ROOT = Path(rostools.__file__).parent


def _typed_names(path: Path) -> set[str]:
    """The names a package's ``if TYPE_CHECKING:`` block imports, as ``X as X`` re-exports."""
    names: set[str] = set()
    for block in ast.parse(path.read_text()).body:
        if isinstance(block, ast.If) and ast.unparse(block.test) == "TYPE_CHECKING":
            for node in block.body:
                assert isinstance(node, ast.ImportFrom), ast.unparse(node)
                assert all(a.asname == a.name for a in node.names), ast.unparse(node)
                names |= {a.name for a in node.names}
    return names


@pytest.mark.parametrize("module", [rostools, rostools.testing])
def test_type_checkers_see_every_public_name(module: object) -> None:
    """The public names are the imports type checkers read, explicitly re-exported."""
    path = Path(module.__file__)  # type: ignore[attr-defined]
    assert set(module.__all__) == _typed_names(path)  # type: ignore[attr-defined]
    assert {"Node", "publish", "record", "read_bag", "Time"} <= set(rostools.__all__)


@pytest.mark.parametrize("module", [rostools, rostools.testing])
def test_every_public_name_loads_and_says_what_it_is(module: object) -> None:
    for name in module.__all__:  # type: ignore[attr-defined]
        value = getattr(module, name)
        assert (value.__doc__ or "").strip(), f"{name} has no docstring"
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        module.nope  # type: ignore[attr-defined]  # noqa: B018


def test_importing_rostools_and_its_pytest_plugin_stays_cheap() -> None:
    """Every CLI start imports ``rostools``, every pytest run the plugin: neither loads the API."""
    code = (
        "import sys\n"
        "def heavy(): return sorted(m for m in sys.modules if m in ('asyncio', 'yaml', 'typing',"
        " 'dataclasses') or m.startswith(('rostools.', 'pytest')))\n"
        "import rostools\n"
        "print(heavy())\n"
        "import pytest, rostools.testing.plugin\n"
        "print([m for m in heavy() if m == 'asyncio' or m.startswith('rostools.')])"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    alone, with_plugin = done.stdout.splitlines()
    assert alone == "[]", alone
    assert with_plugin == "['rostools.testing', 'rostools.testing.plugin']", with_plugin
