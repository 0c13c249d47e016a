"""What the bag verbs say: "1 message", never "1 messages"; ``plot -o`` names what it wrote."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

from tests.support.bagdata import write_sample
from tests.support.env import run_cli

ONE_MESSAGES = re.compile(r"\b1 (messages|records|bags|parts)\b")


def test_one_message_is_singular_in_every_bag_verb(tmp_path: Path) -> None:
    one = write_sample(tmp_path / "one.bag", 1).path  # a single /chatter message
    for name in ("c.bag", "d.bag"):
        shutil.copy(one, tmp_path / name)
    runs = [
        ("convert", str(one), str(tmp_path / "one.mcap")),
        ("filter", str(one), str(tmp_path / "f.bag"), "True"),
        ("recover", str(one), str(tmp_path / "r.bag")),
        ("split", str(one), "--count", "1", "-o", str(tmp_path / "s.bag")),
        ("merge", str(tmp_path / "m.bag"), str(one)),
        ("compress", str(tmp_path / "c.bag")),
        ("reindex", str(tmp_path / "d.bag")),
        ("doctor", str(one)),
    ]
    said = []
    for argv in runs:
        done = run_cli("bag", *argv)
        assert done.returncode == 0, (argv, done.stderr)
        text = done.stdout + done.stderr
        assert "1 message" in text, (argv, text)  # each says how many it handled
        said.append(text)
    wrong = [text for text in said if ONE_MESSAGES.search(text)]
    assert not wrong, wrong


def test_plot_into_a_file_says_what_it_wrote(tmp_path: Path, cli_env: dict[str, str]) -> None:
    bag = write_sample(tmp_path / "s.bag", 400).path
    out = tmp_path / "p.svg"
    env = {**cli_env, "MPLCONFIGDIR": str(tmp_path / "mpl")}
    done = run_cli("bag", "plot", str(bag), "/point/x", "-o", str(out), env=env)
    assert done.returncode == 0, done.stderr
    assert done.stdout == ""  # stdout stays for data
    assert done.stderr == f"wrote {out}: 100 messages over 0.4 s\n"
    assert out.read_text().startswith("<?xml")
