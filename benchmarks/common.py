"""Shared pieces of the benchmarks: results, timing whole processes, the install under test."""

from __future__ import annotations

import contextlib
import json
import os
import shutil
import signal
import socket
import statistics
import subprocess
import sys
import time
import xmlrpc.client
from collections.abc import Callable, Iterator, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
BENCH_VENV = ROOT / "benchmarks" / ".venv"
SYSTEM_PYTHON = "/usr/bin/python3"


@dataclass
class Result:
    """One measurement of rostools beside the real ROS 1 tool, from the same run."""

    name: str
    unit: str
    ours: float
    theirs: float | None
    target: str
    met: bool | None
    note: str = ""

    @property
    def ratio(self) -> float | None:
        """ours / theirs."""
        if self.theirs is None or self.theirs == 0:
            return None
        return self.ours / self.theirs

    def as_dict(self) -> dict[str, object]:
        """For the JSON report."""
        d = asdict(self)
        d["ratio"] = self.ratio
        return d


def rostools_cmd(root: Path = ROOT) -> list[str]:
    """The rostools console script of a normal (non-editable) install, as users get it.

    An editable install adds a meta-path finder that costs ~15 ms at every start-up.
    ``root``: the checkout to install (another one's venv is its own ``benchmarks/.venv``).
    """
    venv = root / "benchmarks" / ".venv"
    exe = venv / "bin" / "rostools"
    stamp = venv / ".installed-from"
    source_mtime = str(max(p.stat().st_mtime for p in (root / "rostools").rglob("*.py")))
    if not exe.exists() or not stamp.exists() or stamp.read_text() != source_mtime:
        if not (venv / "bin" / "python").exists():
            subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
        pip = str(venv / "bin" / "pip")
        subprocess.run(
            [pip, "install", "-q", "--force-reinstall", "--no-deps", str(root)], check=True
        )
        subprocess.run([pip, "install", "-q", str(root)], check=True)
        stamp.write_text(source_mtime)
    return [str(exe)]


def have(tool: str) -> bool:
    """Whether a real ROS 1 tool is on PATH."""
    return shutil.which(tool) is not None


def time_commands(
    commands: dict[str, Sequence[str]],
    runs: int = 30,
    warmup: int = 3,
    env: dict[str, str] | None = None,
) -> dict[str, float]:
    """Median wall time in seconds of each command, runs interleaved so drift hits all alike."""
    samples: dict[str, list[float]] = {k: [] for k in commands}
    for i in range(warmup + runs):
        for key, argv in commands.items():
            start = time.perf_counter()
            proc = subprocess.run(
                argv, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, env=env, check=False
            )
            elapsed = time.perf_counter() - start
            if proc.returncode != 0:
                raise RuntimeError(f"{' '.join(argv)} failed: {proc.stderr.decode()[-500:]}")
            if i >= warmup:
                samples[key].append(elapsed)
    return {k: statistics.median(v) for k, v in samples.items()}


def throughput(fn: Callable[[], int], seconds: float = 2.0) -> float:
    """Items per second of ``fn`` (which returns how many items it did), over ``seconds``."""
    done = 0
    start = time.perf_counter()
    while (elapsed := time.perf_counter() - start) < seconds:
        done += fn()
    return done / elapsed


def write_report(results: list[Result], path: Path) -> None:
    """The JSON report."""
    path.parent.mkdir(parents=True, exist_ok=True)
    payload = {
        "when": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "machine": {"cpus": os.cpu_count(), "python": sys.version.split()[0]},
        "results": [r.as_dict() for r in results],
    }
    path.write_text(json.dumps(payload, indent=2) + "\n")


def merge_latest(results: list[Result], path: Path) -> None:
    """Update ``latest.json`` with these results, keeping the newest of every other benchmark."""
    known: dict[str, dict[str, object]] = {}
    if path.exists():
        for row in json.loads(path.read_text()).get("results", []):
            known[str(row["name"])] = row
    stamp = time.strftime("%Y-%m-%dT%H:%M:%S%z")
    for r in results:
        known[r.name] = {**r.as_dict(), "when": stamp}
    payload = {
        "machine": {"cpus": os.cpu_count(), "python": sys.version.split()[0]},
        "results": list(known.values()),
    }
    path.write_text(json.dumps(payload, indent=2) + "\n")


def free_port() -> int:
    """A loopback TCP port that was free a moment ago."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port: int = s.getsockname()[1]
        return port


def ros_env(master_uri: str) -> dict[str, str]:
    """An environment for benchmark processes: loopback, the given master, a scratch ROS home."""
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS")}
    home = BENCH_VENV.parent / "build" / "ros_home"
    home.mkdir(parents=True, exist_ok=True)
    env.update(
        ROS_MASTER_URI=master_uri, ROS_IP="127.0.0.1", ROS_HOME=str(home), PYTHONUNBUFFERED="1"
    )
    return env


def start(argv: Sequence[str], env: dict[str, str], **kwargs: object) -> subprocess.Popen[bytes]:
    """A process in its own group, stopped later by ``stop`` through its PID."""
    return subprocess.Popen(list(argv), env=env, start_new_session=True, **kwargs)  # type: ignore[call-overload,no-any-return]


def stop(proc: subprocess.Popen[bytes]) -> None:
    """SIGINT, then SIGKILL, to the process group."""
    for sig in (signal.SIGINT, signal.SIGKILL):
        if proc.poll() is None:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(proc.pid, sig)
            try:
                proc.wait(5)
            except subprocess.TimeoutExpired:
                continue


def wait_master(uri: str, timeout: float = 20.0) -> None:
    """Until a master answers at ``uri``."""
    proxy = xmlrpc.client.ServerProxy(uri)
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            proxy.getPid("/bench")
            return
        except OSError:
            time.sleep(0.05)
    raise RuntimeError(f"no master at {uri}")


@contextlib.contextmanager
def master() -> Iterator[str]:
    """A neutral master for data-path benchmarks: the real rosmaster, else rostools core."""
    port = free_port()
    uri = f"http://127.0.0.1:{port}/"
    argv = (
        ["rosmaster", "--core", "-p", str(port)]
        if have("rosmaster")
        else [*rostools_cmd(), "core", "-p", str(port)]
    )
    proc = start(argv, ros_env(uri), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        wait_master(uri)
        yield uri
    finally:
        stop(proc)


def cpu_seconds(pid: int) -> float:
    """User + system CPU time a process (and its reaped children) has used so far."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    ticks = os.sysconf("SC_CLK_TCK")
    return (int(fields[11]) + int(fields[12])) / ticks


def cpp_peer(name: str, folder: Path | None = None) -> str:
    """A roscpp peer (tests/support/cpp, or ``folder``), built once and cached."""
    from tests.support.cppbuild import build, cpp_missing

    reason = cpp_missing()
    if reason is not None:
        raise RuntimeError(f"cannot build the roscpp source: {reason}")
    return str(build(name, folder))


def stamped_arrivals(
    source: Sequence[str], topic: str, count: int, idle: float, env: dict[str, str], timeout: float
) -> list[tuple[int, int]]:
    """(index, steady-clock ns) of each message a roscpp ``sub_stamps`` got from ``source``.

    The subscriber is up, and its subscription with the master, before ``source`` starts;
    both are stopped once it has ``count`` messages or none came for ``idle`` seconds.
    """
    sub = start(
        [cpp_peer("sub_stamps", ROOT / "benchmarks" / "peers"), topic, "--count", str(count),
         "--idle", str(idle)],
        env, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
    )  # fmt: skip
    assert sub.stdout is not None
    if sub.stdout.readline().strip() != b"ready":
        stop(sub)
        raise RuntimeError("sub_stamps did not start")
    time.sleep(0.5)
    src = start(
        source, env, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL
    )
    try:
        out, _ = sub.communicate(timeout=timeout)
    finally:
        stop(sub)
        stop(src)
    lines = (line.split() for line in out.decode().splitlines() if line[:1].isdigit())
    return [(int(k), int(t)) for k, t in lines]


def status_kb(pid: int, field: str = "VmRSS") -> int:
    """A ``/proc/PID/status`` figure in kB (VmRSS, VmHWM); 0 once the process is gone."""
    try:
        text = Path(f"/proc/{pid}/status").read_text()
    except OSError:
        return 0
    for line in text.splitlines():
        if line.startswith(field + ":"):
            return int(line.split()[1])
    return 0


def masters() -> dict[str, list[str]]:
    """Master command lines (the port is appended): ``ours``, and ``theirs`` if installed."""
    found = {"ours": [*rostools_cmd(), "core", "-p"]}
    if have("rosmaster"):
        found["theirs"] = ["rosmaster", "--core", "-p"]
    return found
