"""The API's loop at the end of the process: its blocking work still runs, and holds nothing.

``tests/interop/test_api_exit.py`` ends real scripts against real masters; these are the
parts, without a master.
"""

from __future__ import annotations

import signal
import subprocess
import sys
import textwrap
import threading
from collections.abc import Iterator

import pytest

from rostools._api import exiting
from rostools._api.workers import Workers


def _run(code: str, timeout: float = 60) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-c", textwrap.dedent(code)],
        capture_output=True, text=True, timeout=timeout, check=False,
    )  # fmt: skip


def test_workers_give_results_and_failures() -> None:
    pool = Workers(2)
    assert pool.submit(sum, [1, 2, 3]).result(10) == 6
    failed = pool.submit(int, "x")
    with pytest.raises(ValueError, match="invalid literal"):
        failed.result(10)
    assert [f.result(10) for f in [pool.submit(abs, -n) for n in range(20)]] == list(range(20))
    assert pool._workers <= 2


def test_work_runs_in_the_caller_where_no_thread_may_start(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # Python 3.12 refuses new threads while atexit handlers run
    def refuse(self: threading.Thread) -> None:
        raise RuntimeError("can't create new thread at interpreter shutdown")

    monkeypatch.setattr(threading.Thread, "start", refuse)
    caller = threading.get_ident()
    done = Workers().submit(threading.get_ident)
    assert done.done() and done.result() == caller


def test_the_api_loop_looks_a_host_up_as_the_process_exits() -> None:
    # the defect: asyncio looks host names up on a pool that Python shuts before atexit
    # handlers run, so a node whose master was named by host could not unregister
    done = _run(
        """
        import asyncio, atexit
        from rostools._api import loop

        async def look():
            return await asyncio.get_running_loop().getaddrinfo("localhost", 11311)

        atexit.register(lambda: print("found", bool(loop.run(look()))))
        loop.loop()
        """
    )
    assert done.stdout == "found True\n", done.stderr
    assert done.stderr == ""


def test_work_that_never_ends_does_not_hold_the_exit() -> None:
    # a blocking service handler that never returns: a pool's threads are joined at exit
    done = _run(
        """
        import threading
        from rostools._api import loop

        started = threading.Event()

        def forever():
            started.set()
            threading.Event().wait()

        loop.loop().call_soon_threadsafe(loop.loop().run_in_executor, None, forever)
        started.wait()
        print("leaving")
        """
    )
    assert (done.returncode, done.stdout, done.stderr) == (0, "leaving\n", "")


@pytest.fixture
def sigterm_undecided(monkeypatch: pytest.MonkeyPatch) -> Iterator[None]:
    """SIGTERM's handler as the test found it afterwards, and the API yet to look at it."""
    saved = signal.getsignal(signal.SIGTERM)
    monkeypatch.setattr(exiting, "_sigterm_decided", False)
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, saved)


@pytest.mark.usefixtures("sigterm_undecided")
def test_sigterm_is_taken_only_where_the_program_left_it_to_python() -> None:
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    exiting.take_sigterm()
    assert signal.getsignal(signal.SIGTERM) is exiting._on_sigterm


@pytest.mark.usefixtures("sigterm_undecided")
def test_a_programs_own_sigterm_handler_is_left_alone() -> None:
    def mine(signum: int, frame: object) -> None:
        pass

    signal.signal(signal.SIGTERM, mine)
    exiting.take_sigterm()
    assert signal.getsignal(signal.SIGTERM) is mine
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    exiting.take_sigterm()  # decided once, when the first node started
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL
