"""Build the roscpp peers in ``tests/support/cpp`` with g++, once per source and flags.

``build("pub_rate")`` compiles ``tests/support/cpp/pub_rate.cpp`` against the Debian ROS 1 libraries
and returns the path of the executable, cached under ``benchmarks/build/cpp/`` (gitignored;
``ROSTOOLS_CPP_CACHE`` overrides) and named by a hash of the compiler, the flags, the source and
the shared headers, so repeated test runs and benchmarks reuse it. A build writes a temporary
file and renames it into place under a per-program lock, so concurrent pytest processes (or
threads) neither corrupt an executable nor compile the same one twice.

``cpp_missing()`` says why nothing can be built here (no g++, no roscpp headers), for
``pytest.skip``. Run ``python -m tests.support.cppbuild [NAME ...]`` to build ahead of time.
"""

from __future__ import annotations

import fcntl
import functools
import hashlib
import os
import shutil
import subprocess
import sys
import threading
from collections.abc import Iterable
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent.parent
SOURCES = Path(__file__).with_name("cpp")
CACHE = Path(os.environ.get("ROSTOOLS_CPP_CACHE", ROOT / "benchmarks" / "build" / "cpp"))
CXX = os.environ.get("CXX", "g++")
CXXFLAGS = ["-O2", "-std=c++17", "-pthread"]
# The Debian packages put headers in /usr/include and libraries in the default search path;
# no pkg-config needed. Order matters for static resolution: users before what they use.
LIBS = [
    "-lroscpp",
    "-lrosconsole",
    "-lroscpp_serialization",
    "-lrostime",
    "-lxmlrpcpp",
    "-lcpp_common",
    "-lboost_system",
]
# Added when topic_tools is installed: sub_count then subscribes with topic_tools::ShapeShifter.
TOPIC_TOOLS = ["-DHAVE_TOPIC_TOOLS=1", "-ltopic_tools"]
PROGRAMS = ("pub_rate", "sub_count", "listener", "talker", "add_two_ints_server", "log_levels")

_locks_guard = threading.Lock()
_locks: dict[str, threading.Lock] = {}


class CppBuildError(RuntimeError):
    """A peer could not be built: the toolchain is missing or the compiler failed."""


@functools.cache
def _include_dirs() -> tuple[Path, ...]:
    """The compiler's own header search path (with CPATH and friends), as ``g++ -v`` shows it.

    Looking for files there is instant; preprocessing <ros/ros.h> to probe it takes seconds.
    """
    try:
        proc = subprocess.run(
            [CXX, "-x", "c++", "-E", "-v", "-", "-o", os.devnull],
            input="",
            capture_output=True,
            text=True,
            timeout=60,
            check=False,
        )
    except (OSError, subprocess.TimeoutExpired):
        return ()
    # The directories are the indented lines between the "search starts here:" headings and
    # "End of search list." (-iquote dirs first, then -I, CPATH and the system ones).
    dirs: list[Path] = []
    listing = False
    for line in proc.stderr.splitlines():
        if line.endswith("search starts here:"):
            listing = True
        elif line == "End of search list.":
            break
        elif listing and line.startswith(" "):
            dirs.append(Path(line.strip()))
    return tuple(dirs)


def _has_header(header: str) -> bool:
    return any((directory / header).is_file() for directory in _include_dirs())


@functools.cache
def cpp_missing() -> str | None:
    """Why the C++ peers cannot be built here, or None when they can."""
    if shutil.which(CXX) is None:
        return f"no C++ compiler {CXX!r} (apt-get install g++)"
    for header in ("ros/ros.h", "std_msgs/String.h", "sensor_msgs/Image.h"):
        if not _has_header(header):
            return f"<{header}> not found (run scripts/install-ros1-peers.sh)"
    return None


@functools.cache
def has_topic_tools() -> bool:
    """Whether topic_tools (ShapeShifter, for sub_count's --type any) is installed."""
    return _has_header("topic_tools/shape_shifter.h")


@functools.cache
def _compiler_id() -> str:
    """The compiler's version line: a compiler upgrade must not reuse old executables."""
    proc = subprocess.run([CXX, "--version"], capture_output=True, text=True, check=False)
    return proc.stdout.splitlines()[0] if proc.stdout else CXX


def command(name: str, output: Path, folder: Path | None = None) -> list[str]:
    """The g++ command line that builds ``folder/name.cpp`` (default SOURCES) into ``output``."""
    folder = folder or SOURCES
    extra = TOPIC_TOOLS if has_topic_tools() else []
    source = folder / f"{name}.cpp"
    return [CXX, *CXXFLAGS, f"-I{SOURCES}", str(source), "-o", str(output), *extra, *LIBS]


def _key(name: str, folder: Path) -> str:
    digest = hashlib.sha256()
    digest.update(_compiler_id().encode())
    # Flags without the paths in them: moving the checkout keeps the cache valid.
    line = " ".join(command(name, Path("OUT"), folder))
    digest.update(line.replace(str(folder), "SRC").replace(str(SOURCES), "SRC").encode())
    digest.update((folder / f"{name}.cpp").read_bytes())
    for header in sorted(SOURCES.glob("*.h")):
        digest.update(header.name.encode() + b"\0" + header.read_bytes())
    return digest.hexdigest()[:16]


def build(name: str, folder: Path | None = None) -> Path:
    """The executable for ``<folder>/<name>.cpp`` (default: tests/support/cpp), built if new.

    Other folders' peers (benchmarks/peers) include ``peer.h`` from tests/support/cpp too.
    Raises CppBuildError when the toolchain is missing or the compiler fails (with its output).
    """
    folder = folder or SOURCES
    if not (folder / f"{name}.cpp").is_file():
        raise CppBuildError(f"no such peer: {folder / name}.cpp")
    if reason := cpp_missing():
        raise CppBuildError(reason)
    target = CACHE / f"{name}-{_key(name, folder)}"
    if os.access(target, os.X_OK):
        return target
    CACHE.mkdir(parents=True, exist_ok=True)
    with _locks_guard:
        thread_lock = _locks.setdefault(name, threading.Lock())
    # flock serializes processes, the thread lock threads of this one (flock is per open file,
    # so two threads would each get it); the re-check skips work another one finished.
    with thread_lock, open(CACHE / f".{name}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if os.access(target, os.X_OK):
            return target
        temp = target.with_name(f".{target.name}.{os.getpid()}.tmp")
        try:
            proc = subprocess.run(
                command(name, temp, folder),
                capture_output=True,
                text=True,
                timeout=600,
                check=False,
            )
            if proc.returncode != 0:
                raise CppBuildError(f"g++ failed to build {name}:\n{proc.stderr[-4000:]}")
            os.replace(temp, target)
        finally:
            temp.unlink(missing_ok=True)
        for stale in CACHE.glob(f"{name}-*"):
            if stale != target:
                stale.unlink(missing_ok=True)  # older builds of this program
    return target


def build_many(names: Iterable[str] = PROGRAMS, jobs: int | None = None) -> dict[str, Path]:
    """Build several peers in parallel (one compiler per core); their executables by name."""
    names = list(names)
    with ThreadPoolExecutor(max_workers=jobs or os.cpu_count() or 1) as pool:
        paths = list(pool.map(build, names))
    return dict(zip(names, paths, strict=True))


def main(argv: list[str]) -> int:
    """Build the named peers (default: all) and print each executable's path."""
    try:
        for path in build_many(argv or PROGRAMS).values():
            print(path)
    except CppBuildError as exc:
        print(exc, file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
