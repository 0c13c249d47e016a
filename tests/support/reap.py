"""The suite's processes die with pytest: each process group a test starts is told to the
plugin's reaper (``rostools.testing.reaper``), which stops the groups still listed when the
process that started them ends, however it ends: Ctrl-C in a teardown that had not stopped
them all yet, SIGTERM or SIGKILL to pytest or to an xdist worker.
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import threading
from collections.abc import Callable, Sequence
from typing import Any

from rostools.testing.process import _REAPER

#: The process groups told to the reaper, each with whether it may still have a process.
_reaped: dict[int, Callable[[], bool]] = {}
_reaped_lock = threading.Lock()


def reap_with_pytest(group: int, running: Callable[[], bool] | None = None) -> None:
    """Have the reaper stop process group ``group`` if this process ends before it does.

    ``running`` says whether the group may still have a process (by default: whether it has
    one). The groups that have none are forgotten here, before their IDs are given out again
    (this machine may have only 32,768, and a run starts thousands of processes).
    """
    forget_ended()
    with _reaped_lock:
        _reaped[group] = running or (lambda: group_left(group))
    _REAPER.tell(f"+{group}")


def forget(group: int) -> None:
    """Tell the reaper that process group ``group`` has ended."""
    with _reaped_lock:
        if _reaped.pop(group, None) is None:
            return
    _REAPER.tell(f"-{group}")


def forget_ended() -> None:
    """Forget every group told to the reaper that has ended (a test waited for it alone)."""
    with _reaped_lock:
        groups = list(_reaped.items())
    for group, running in groups:
        if not running():
            forget(group)


def run(
    argv: Sequence[str],
    *,
    input: str | bytes | None = None,
    timeout: float | None = None,
    text: bool = True,
    **kwargs: Any,
) -> subprocess.CompletedProcess[Any]:
    """``subprocess.run(argv, capture_output=True, check=False)``, in a session of its own that
    the reaper stops if pytest dies while it runs; on a timeout its whole group is killed."""
    stdin = subprocess.PIPE if input is not None else kwargs.pop("stdin", subprocess.DEVNULL)
    with subprocess.Popen(
        argv, stdin=stdin, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=text,
        start_new_session=True, **kwargs,
    ) as popen:  # fmt: skip
        reap_with_pytest(popen.pid)
        try:
            out, err = popen.communicate(input, timeout=timeout)
        except BaseException:  # a timeout, or Ctrl-C: what it started goes with it
            with contextlib.suppress(ProcessLookupError):
                os.killpg(popen.pid, signal.SIGKILL)
            popen.communicate()
            forget(popen.pid)
            raise
        if not group_left(popen.pid):  # else the reaper still stops what it left running
            forget(popen.pid)
    return subprocess.CompletedProcess(popen.args, popen.returncode, out, err)


def group_left(group: int) -> bool:
    """Whether any process (a zombie too) is left in process group ``group``."""
    try:
        os.killpg(group, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True
