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


def _stub_names() -> set[str]:
    tree = ast.parse((ROOT / "__init__.pyi").read_text())
    names: set[str] = set()
    for node in tree.body:
        if isinstance(node, ast.ImportFrom):
            names |= {a.asname or a.name for a in node.names}
    return names


def test_the_stub_gives_every_public_name_a_type() -> None:
    assert set(rostools.__all__) == _stub_names()


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
