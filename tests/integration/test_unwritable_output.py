"""An output that cannot be written is exit 2 in every command, with one line naming it.

It was 2 for ``record -O``, 1 for convert, filter, recover, split, merge and ``node graph -o
x.svg``, 3 for ``bag plot -o`` and ``node graph -o x.dot``, and an internal error for ``param
dump``.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.support.bagdata import write_sample
from tests.support.env import run_cli

#: command, with ``{out}`` where the output goes and ``{bag}`` for an input bag
OFFLINE = [
    ["bag", "plot", "{bag}", "/point/x", "-o", "{out}.png"],
    ["bag", "convert", "{bag}", "{out}.mcap"],
    ["bag", "filter", "{bag}", "{out}.bag", "topic == '/point'"],
    ["bag", "recover", "{bag}", "{out}.bag"],
    ["bag", "split", "{bag}", "--count", "10", "-o", "{out}.bag"],
    ["bag", "merge", "{out}.bag", "{bag}"],
]
LIVE = [
    ["bag", "record", "-a", "-O", "{out}.bag"],
    ["param", "dump", "{out}.yaml"],
    ["node", "graph", "-o", "{out}.dot"],
    ["node", "graph", "-o", "{out}.svg"],
]


def _check(argv: list[str], env: dict[str, str], out: Path, bag: Path | None = None) -> None:
    args = [a.format(out=out, bag=bag) for a in argv]
    done = run_cli(*args, env=env, timeout=60)
    assert done.returncode == 2, done.stderr
    assert done.stderr.startswith(f"rostools: cannot write {out}"), done.stderr
    assert done.stderr.count("\n") == 1, done.stderr


@pytest.mark.parametrize("argv", LIVE, ids=" ".join)
def test_live_commands(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path, argv: list[str]
) -> None:
    _check(argv, cli_env, tmp_path / "no" / "such" / "out")


@pytest.mark.parametrize("argv", OFFLINE, ids=" ".join)
def test_bag_commands(cli_env: dict[str, str], tmp_path: Path, argv: list[str]) -> None:
    bag = write_sample(tmp_path / "s.bag", 40).path
    _check(argv, cli_env, tmp_path / "no" / "such" / "out", bag)
