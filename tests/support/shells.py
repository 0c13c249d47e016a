"""Real interactive bash, zsh and fish, driven through a terminal (pexpect), with our scripts.

``Shell.complete(text, tabs)`` types ``text``, presses TAB, then turns the line into
``echo LINEX: <line>`` and runs it, so the test reads exactly the line the shell completed.
``Shell.offers(text)`` reads the list a shell shows when several candidates fit.
"""

from __future__ import annotations

import contextlib
import re
import shutil
import sys
import time
from pathlib import Path

import pexpect

ROOT = Path(__file__).resolve().parent.parent.parent
SCRIPTS = {
    "bash": ROOT / "completions" / "rostools.bash",
    "zsh": ROOT / "completions" / "_rostools",
    "fish": ROOT / "completions" / "rostools.fish",
}
_ANSI = re.compile(r"\x1b\[[0-9;?]*[a-zA-Z]|\x1b[()][A-Z0-9]|\x1b[>=]|[\r\x07\x08]")


def shell_missing(shell: str) -> str | None:
    """Why ``shell`` cannot be tested here, or None."""
    if shutil.which(shell) is None:
        return f"{shell} is not installed (scripts/install-ros1-peers.sh installs it)"
    return None


def clean(text: str) -> str:
    """Terminal output without escape sequences, carriage returns and bells."""
    return _ANSI.sub("", text)


class Shell:
    """One interactive shell with rostools' completion loaded."""

    def __init__(self, shell: str, env: dict[str, str], cwd: Path) -> None:
        self.name = shell
        env = dict(env)
        env["PATH"] = f"{Path(sys.executable).parent}:{env.get('PATH', '/usr/bin:/bin')}"
        env["TERM"] = "xterm"
        argv, setup = {
            "bash": (["--norc", "--noprofile"], f"source {SCRIPTS['bash']}"),
            "zsh": (["-f"], f"autoload -Uz compinit && compinit -u; source {SCRIPTS['zsh']}"),
            "fish": (["--no-config"], f"source {SCRIPTS['fish']}"),
        }[shell]
        self.child = pexpect.spawn(
            shell, argv, env=env, cwd=str(cwd), encoding="utf-8", timeout=10, dimensions=(50, 250)
        )
        prompt = "function fish_prompt; echo 'READY> '; end" if shell == "fish" else "PS1='READY> '"
        self.child.sendline(prompt)
        self.child.sendline(setup)
        self.child.sendline("echo SET''UP")
        self.child.expect("SETUP")
        self._drain()

    def _drain(self, settle: float = 0.3) -> str:
        """Everything the terminal printed until it has been quiet for ``settle`` seconds."""
        seen = []
        while True:
            try:
                seen.append(self.child.read_nonblocking(65536, timeout=settle))
            except pexpect.TIMEOUT:
                return clean("".join(seen))

    def complete(self, text: str, tabs: int = 1) -> str:
        """The command line after typing ``text`` and pressing TAB ``tabs`` times."""
        self.child.send(text)
        for _ in range(tabs):
            self.child.send("\t")
        # The line editor takes keys in order, so what follows waits for the completion; the
        # quiet spell only lets a list it printed pass before the line is read back.
        self._drain()
        # Ctrl-A, to the start of the line; the quotes keep the echoed input from matching
        self.child.send("\x01echo LINE''X: \r")
        self.child.expect(r"LINEX: ([^\r\n]*)\r?\n")
        line: str = self.child.match.group(1)
        self.child.expect("READY> ")
        return clean(line).strip()

    def offers(self, text: str, *listed: str, timeout: float = 10) -> str:
        """What the shell lists after ``text`` and two TABs (bash lists on the second), read
        until every one of ``listed`` has shown, and then until the terminal is quiet."""
        self.child.send(text + "\t\t")
        seen = []
        deadline = time.monotonic() + timeout
        while not all(name in clean("".join(seen)) for name in listed):
            if time.monotonic() > deadline:
                raise AssertionError(f"{self.name} listed no {listed}: {clean(''.join(seen))!r}")
            with contextlib.suppress(pexpect.TIMEOUT):
                seen.append(self.child.read_nonblocking(65536, timeout=0.1))
        shown = clean("".join(seen)) + self._drain()
        self.child.send("\x03")  # drop the line
        self._drain()
        return shown

    def close(self) -> None:
        """End the shell (and anything it still runs)."""
        self.child.close(force=True)
