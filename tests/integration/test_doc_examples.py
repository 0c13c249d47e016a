"""Every example in README.md and docs/*.md, run against a live graph (tests/support/docblocks).

One graph for them all: ``rostools core`` on a free port, ``docs_graph.py`` (the topics,
services and action the examples name), and in each block's own folder a copy of the files
they name (tests/support/docfiles.py). The blocks run side by side; the commands of a block
run in order, as a user types them. A command must exit 0 (or its block's ``exit``), and
print the output shown, line by line in order (``...`` stands for anything). A command that
runs until stopped (``topic echo /scan``) is left running while the rest of its block runs,
as in a second terminal, and stopped with Ctrl-C (SIGINT) at the end of the block, once it
has done what it is for (printed a message, connected to a peer): Ctrl-C on such a command is
exit 0, where a command not meant to run until stopped would exit 130.
"""

from __future__ import annotations

import ast
import contextlib
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import xmlrpc.client
from collections.abc import Callable, Iterator
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import pytest

from tests.support.docblocks import Block, Command, blocks, documents
from tests.support.docfiles import write_all
from tests.support.env import ROOT
from tests.support.procs import (
    Proc,
    core_and_env,
    free_port,
    group_members,
    wait_for,
)

#: A command that ends by itself must end within this (the longest, trigger --after 10s).
FINITE_LIMIT = 120.0
#: A command that runs until stopped must do what it is for within this.
READY_LIMIT = 30.0
ALL = [b for doc in documents(ROOT) for b in blocks(doc) if b.lang in ("console", "sh", "python")]
RUN = [b for b in ALL if "not run" not in b.markers and "excerpt" not in b.markers]


@dataclass
class Graph:
    """The live graph: the master's URI and an environment for commands on it."""

    uri: str
    env: dict[str, str]
    files: Path


@pytest.fixture(scope="module")
def graph(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Graph]:
    """``rostools core``, the docs' graph on it, and the files the examples name."""
    home = tmp_path_factory.mktemp("docs-graph")
    core, env = core_and_env(home)
    node_env = dict(env, ROSTOOLS_MSG_PATH=str(ROOT / "tests" / "support" / "doc_types"))
    script = ROOT / "tests" / "support" / "rt_nodes" / "docs_graph.py"
    node = Proc([sys.executable, str(script)], env=node_env)
    try:
        node.expect("^ready", timeout=60)
        files = home / "files"
        write_all(files)
        env["PATH"] = f"{Path(sys.executable).parent}{os.pathsep}{os.environ.get('PATH', '')}"
        yield Graph(env["ROS_MASTER_URI"], env, files)
    finally:
        node.stop()
        core.stop()


def _pattern(shown: str) -> re.Pattern[str]:
    """A shown output line as a pattern: ``...`` matches anything, trailing blanks are free."""
    return re.compile(".*".join(re.escape(part) for part in shown.split("...")) + r"\s*")


def missing_output(shown: list[str], printed: str) -> str | None:
    """The first shown line that the printed lines lack, in order; None when all are there."""
    lines = iter(printed.splitlines())
    for want in shown:
        if want.strip() in ("", "..."):
            continue
        pattern = _pattern(want)
        if not any(pattern.fullmatch(line) for line in lines):
            return want
    return None


def node_pids(uri: str) -> dict[str, int]:
    """Each node the master knows, and its PID (what answers)."""
    with xmlrpc.client.ServerProxy(uri) as master:
        state = master.getSystemState("/docs")[2]
        names = {n for part in state for _, nodes in part for n in nodes}
        pids = {}
        for name in names:
            with contextlib.suppress(OSError, xmlrpc.client.Error):
                code, _, node_uri = master.lookupNode("/docs", name)
                if code == 1:
                    with xmlrpc.client.ServerProxy(node_uri) as peer:
                        pids[name] = int(peer.getPid("/docs")[2])
    return pids


def connected(uri: str, group: int) -> bool:
    """Whether a node of process group ``group`` has a live connection to a peer."""
    members = set(group_members(group))
    for name, pid in node_pids(uri).items():
        if pid not in members:
            continue
        with contextlib.suppress(OSError, xmlrpc.client.Error):
            with xmlrpc.client.ServerProxy(uri) as master:
                node_uri = master.lookupNode("/docs", name)[2]
            with xmlrpc.client.ServerProxy(node_uri) as peer:
                if any(entry[5] for entry in peer.getBusInfo("/docs")[2]):
                    return True
    return False


def _bounded(argv: str, *flags: str) -> bool:
    return any(re.search(rf"(^|\s){re.escape(f)}(\s|=|$)", argv) for f in flags)


def until_stopped(command: str) -> str | None:
    """What a command that runs until stopped must do first ("printed", "connected", or a
    line it prints); None for a command that ends by itself."""
    if re.match(r"rostools core\b", command):
        return "press Ctrl-C to stop"
    if re.match(r"rostools topic (echo|hz)\b", command):
        return None if _bounded(command, "-n", "--timeout", "-b") else "printed"
    if re.match(r"rostools action status\b", command):
        return "printed"
    if re.match(r"rostools topic pub\b", command):
        return None if _bounded(command, "-1", "--once", "-f") else "connected"
    if re.match(r"rostools tf pub\b", command):
        return "Press Ctrl-C to stop"
    if re.match(r"rostools tf monitor\b", command):
        return None if _bounded(command, "-n", "--count", "-b", "--bag") else "printed"
    if re.match(r"rostools topic plot\b", command):
        return None if _bounded(command, "-n", "--timeout") else "connected"
    if re.match(r"rostools bag (record|snapshot)\b", command):
        ends = _bounded(command, "--duration") and not _bounded(command, "--split")
        return None if ends else "connected"
    return None


class Shell:
    """One command of an example in ``bash -o pipefail``, in the block's folder; what it
    prints goes to files there, read as it runs."""

    def __init__(self, command: Command, env: dict[str, str], cwd: Path) -> None:
        self.command = command
        self.cwd = cwd
        self.out = cwd / f".stdout-{command.line}"
        self.err = cwd / f".stderr-{command.line}"
        script = (
            f"{{ {command.text}\n}} >{shlex.quote(str(self.out))} 2>{shlex.quote(str(self.err))}"
        )
        self.proc = Proc(["bash", "-o", "pipefail", "-c", script], env=env, cwd=cwd)

    def printed(self) -> str:
        """What it has printed so far, stdout then stderr."""
        return "".join(p.read_text(errors="replace") for p in (self.out, self.err) if p.exists())

    def finish(self, limit: float) -> tuple[int, str]:
        """Its exit code and everything it printed, once it ends (stopped after ``limit``)."""
        try:
            code = self.proc.popen.wait(limit)
        except subprocess.TimeoutExpired:
            self.proc.stop()
            return -1, f"it did not end within {limit:.0f} s; it printed:\n{self.printed()}"
        self.proc.stop()  # anything it left in its process group
        return code, self.printed()

    def interrupt(self, limit: float) -> tuple[int, str]:
        """Ctrl-C to its rostools processes (a pipe that reads from them then ends by
        itself); its exit code and output."""
        for pid in group_members(self.proc.pid):
            with contextlib.suppress(OSError):
                argv = Path(f"/proc/{pid}/cmdline").read_bytes().split(b"\0")
                if any(b"rostools" in part for part in argv[:2]):
                    os.kill(pid, signal.SIGINT)
        return self.finish(limit)

    def ready(self, what: str, uri: str) -> Callable[[], bool]:
        """Whether it has done ``what`` yet (see ``until_stopped``)."""
        if what == "connected":
            return lambda: connected(uri, self.proc.pid)
        if what == "printed":
            redirect = re.search(r">\s*(\S+)\s*$", self.command.text)
            target = self.cwd / redirect.group(1) if redirect else self.out
            return lambda: target.is_file() and target.stat().st_size > 0
        return lambda: what in self.printed()


def run_shell(block: Block, graph: Graph, cwd: Path) -> list[str]:
    """Run a console or sh block; what went wrong, one line per failure."""
    expected = int(block.markers.get("exit", "0"))
    compare = "output not compared" not in block.markers
    failures: list[str] = []
    running: list[tuple[Shell, str]] = []
    env = dict(graph.env, HOME=str(cwd / ".home"))

    def check(shell: Shell, code: int, printed: str) -> None:
        cmd = shell.command
        if code != expected:
            failures.append(f"line {cmd.line}: `{cmd.text}` exited {code}, not {expected}:\n"
                            f"{printed[-1500:]}")  # fmt: skip
        elif compare and (lacks := missing_output(cmd.output, printed)) is not None:
            failures.append(f"line {cmd.line}: `{cmd.text}` did not print {lacks!r}:\n"
                            f"{printed[-1500:]}")  # fmt: skip

    try:
        for command in block.commands():
            what = until_stopped(command.text)
            shell_env = env
            if command.text.startswith("rostools core"):  # a master of its own, beside ours
                shell_env = dict(env, ROS_MASTER_URI=f"http://127.0.0.1:{free_port()}")
            shell = Shell(command, shell_env, cwd)
            if what is None:
                check(shell, *shell.finish(FINITE_LIMIT))
                continue
            running.append((shell, what))
            done = shell.ready(what, graph.uri)
            try:
                wait_for(
                    lambda s=shell, d=done: d() or s.proc.popen.poll() is not None,  # type: ignore[misc]
                    READY_LIMIT,
                    f"`{command.text}` to have {what}",
                )
            except AssertionError as err:
                failures.append(f"line {command.line}: {err}")
    finally:
        for shell, _ in running:
            if shell.proc.popen.poll() is None:
                check(shell, *shell.interrupt(30))
            else:
                check(shell, *shell.finish(30))
    return failures


def run_python(block: Block, graph: Graph, cwd: Path) -> list[str]:
    """Run a python block as a script; what went wrong."""
    (cwd / "example.py").write_text(block.body)
    env = dict(graph.env, HOME=str(cwd / ".home"))
    try:
        done = subprocess.run(
            [sys.executable, "example.py"], cwd=cwd, env=env, capture_output=True, text=True,
            timeout=FINITE_LIMIT, check=False, start_new_session=True,
        )  # fmt: skip
    except subprocess.TimeoutExpired:
        return [f"it did not end within {FINITE_LIMIT:.0f} s"]
    if done.returncode != 0:
        return [f"it exited {done.returncode}:\n{(done.stdout + done.stderr)[-2000:]}"]
    return []


def run_block(block: Block, graph: Graph, scratch: Path) -> list[str]:
    """Run one example in a fresh copy of the files; what went wrong, each under its place."""
    cwd = scratch / re.sub(r"\W", "_", block.where)
    shutil.copytree(graph.files, cwd)
    runner = run_python if block.lang == "python" else run_shell
    return [f"{block.where}: {failure}" for failure in runner(block, graph, cwd)]


@pytest.mark.timeout(900)  # the blocks side by side: about 30 s here, more under load
def test_every_example_in_the_docs_runs(graph: Graph, tmp_path: Path) -> None:
    chosen = [b for b in RUN if "xfail" not in b.markers]
    assert len(chosen) >= 20, [b.where for b in chosen]
    with ThreadPoolExecutor(max_workers=4) as pool:
        results = list(pool.map(lambda b: run_block(b, graph, tmp_path), chosen))
    failures = [f for found in results for f in found]
    assert not failures, "\n\n".join(failures)


XFAIL = [b for b in RUN if "xfail" in b.markers]
if XFAIL:  # an example known to fail, until what its marker names is fixed

    @pytest.mark.parametrize(
        "block",
        [pytest.param(b, id=b.where, marks=pytest.mark.xfail(reason=b.markers["xfail"],
                                                             strict=True)) for b in XFAIL],
    )  # fmt: skip
    def test_an_example_marked_xfail_still_fails(
        block: Block, graph: Graph, tmp_path: Path
    ) -> None:
        assert run_block(block, graph, tmp_path) == []


def test_every_excerpt_matches_its_source() -> None:
    """A block marked ``excerpt: PATH`` is that file's code (docstrings aside), not a copy
    that drifted: its imports and each of its functions, compared as syntax trees."""
    excerpts = [b for b in ALL if "excerpt" in b.markers]
    assert excerpts
    for block in excerpts:
        source = ROOT / block.markers["excerpt"].split(",")[0].strip()
        theirs = {_key(n): _tree(n) for n in ast.parse(source.read_text()).body}
        for node in ast.parse(block.body).body:
            assert theirs.get(_key(node)) == _tree(node), f"{block.where}: {_key(node)}"


def _key(node: ast.stmt) -> str:
    return getattr(node, "name", "") or ast.dump(node)


def _tree(node: ast.stmt) -> str:
    body = getattr(node, "body", None)
    if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant):
        node = type(node)(**{**node.__dict__, "body": body[1:]})  # without its docstring
    return ast.dump(node)
