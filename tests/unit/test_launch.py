"""``rostools.cli.launch``: the command line read without Typer, or handed to it."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from rostools.cli.launch import QUICK, _NotQuick, parse

SPECS: dict[str, Any] = json.loads(Path(QUICK).read_text())


def test_values_as_typer_passes_them() -> None:
    get = SPECS["param get"]
    assert parse(get, ["/a", "-p", "--format", "json"]) == {
        "name": "/a", "pretty": True, "verbose": False, "fmt": "json",
    }  # fmt: skip
    assert parse(get, ["--format=yaml", "--", "-x"])["name"] == "-x"
    md5 = SPECS["msg md5"]
    assert parse(md5, ["T", "--msg-path", "a", "--msg-path", "b"])["msg_path"] == [
        Path("a"),
        Path("b"),
    ]
    assert parse(SPECS["service type"], ["/s", "--timeout", "2.5"])["timeout"] == 2.5


@pytest.mark.parametrize(
    "argv",
    [
        [],  # a missing argument: Typer says so
        ["/a", "/b"],  # one too many
        ["/a", "-h"],  # help
        ["/a", "--bogus"],  # an unknown option
        ["/a", "-pv"],  # bundled flags
        ["/a", "-F", "xml"],  # a bad choice
        ["/a", "-F"],  # a value missing
        ["/a", "--pretty=1"],  # a value given to a flag
    ],
)
def test_anything_unusual_goes_to_typer(argv: list[str]) -> None:
    with pytest.raises(_NotQuick):
        parse(SPECS["param get"], argv)
    with pytest.raises(_NotQuick):
        parse(SPECS["service type"], ["/s", "--timeout", "nan"])


def test_a_missing_list_argument_goes_to_typer() -> None:
    """``node info`` needs at least one node: with none, Typer says so."""
    with pytest.raises(_NotQuick):
        parse(SPECS["node info"], ["-q"])
    assert parse(SPECS["node info"], ["/a", "/b", "-q"])["nodes"] == ["/a", "/b"]


def test_a_quick_command_starts_without_typer(tmp_path: Path) -> None:
    """The point of the launcher: no Typer, no xmlrpc.client, no dataclasses at start-up."""
    code = (
        "import sys\n"
        "from rostools.cli import main\n"
        "try:\n    main(['msg', 'md5', 'std_msgs/String'])\n"
        "except SystemExit:\n    pass\n"
        "print(sorted(m for m in ('typer', 'xmlrpc.client', 'dataclasses') if m in sys.modules))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.splitlines()[-1] == "[]", done.stdout


def test_the_quick_path_imports_little() -> None:
    """What quick commands import leaves out typing, yaml, socket, dataclasses (2-20 ms each).

    Every module quick.json runs a command from but ``msg md5``'s, which reads the type store
    (JSON), and what those import on the way.
    """
    modules = sorted({s["target"].partition(":")[0] for s in SPECS.values() if s["target"]})
    modules.remove("rostools.cli.msg.query")
    assert "rostools.cli.topic.query" in modules, modules
    imports = [*modules, "rostools.cli.launch", "rostools.cli.param.plainyaml",
               "rostools.rosgraph.nodeapi", "rostools.rosgraph.topics"]  # fmt: skip
    code = (
        "import sys\n"
        f"import {', '.join(imports)}\n"
        "heavy = ('typing', 'yaml', 'socket', 'json', 'encodings.idna', 'base64', 'ast',\n"
        "         'dataclasses', 'concurrent.futures', 'logging', 'typer', 'click')\n"
        "print(sorted(m for m in heavy if m in sys.modules))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.splitlines()[-1] == "[]", done.stdout
