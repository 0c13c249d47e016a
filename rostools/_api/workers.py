"""The API loop's blocking work, on daemon threads that serve until the process ends.

asyncio runs blocking work (looking a host name up, reading a big XML-RPC body, a blocking
service handler) on its loop's default executor. A ``concurrent.futures`` pool refuses work
once the interpreter starts to exit, before ``atexit`` handlers run and while threads that
outlive the main one still run. A node whose master was named by host name
(``http://localhost:11311``) then could neither unregister at exit nor reach its master
("cannot schedule new futures after interpreter shutdown"). These workers take work until
the process ends, and being daemon threads, a handler that never returns does not hold it.
"""

from __future__ import annotations

import concurrent.futures
import functools
import queue
import threading
from collections.abc import Callable
from typing import Any, ParamSpec, TypeVar

P = ParamSpec("P")
T = TypeVar("T")

_Job = tuple["concurrent.futures.Future[Any]", Callable[[], Any]]


class Workers(concurrent.futures.ThreadPoolExecutor):
    """An executor of daemon threads, started as work comes (up to ``max_workers``) and kept.

    A ``ThreadPoolExecutor`` only by type: asyncio takes no other kind as a loop's default.
    Where no thread may start (Python 3.12 refuses new threads while ``atexit`` handlers
    run) and none is there to take the work, it runs in the caller.
    """

    def __init__(self, max_workers: int | None = None) -> None:
        super().__init__(max_workers, thread_name_prefix="rostools-api-worker")
        self._jobs: queue.SimpleQueue[_Job] = queue.SimpleQueue()
        #: One count per worker that finished a job and waits for the next (as the pool's).
        self._waiting = threading.Semaphore(0)
        self._workers = 0
        self._count_lock = threading.Lock()

    def submit(
        self, fn: Callable[P, T], /, *args: P.args, **kwargs: P.kwargs
    ) -> concurrent.futures.Future[T]:
        """Run ``fn(*args, **kwargs)`` on a worker; its future."""
        future: concurrent.futures.Future[T] = concurrent.futures.Future()
        self._jobs.put((future, functools.partial(fn, *args, **kwargs)))
        if self._waiting.acquire(blocking=False):
            return future  # a waiting worker takes it
        with self._count_lock:
            start = self._workers < self._max_workers
            self._workers += start
        if start:
            try:
                threading.Thread(
                    target=self._work, name=f"rostools-api-worker-{self._workers}", daemon=True
                ).start()
            except RuntimeError:  # no new thread now: the interpreter is exiting
                with self._count_lock:
                    self._workers -= 1
                    alone = self._workers == 0
                if alone:
                    self._run_queued()
        return future

    def _work(self) -> None:
        while True:
            _run(self._jobs.get())
            self._waiting.release()

    def _run_queued(self) -> None:
        while True:
            try:
                job = self._jobs.get_nowait()
            except queue.Empty:
                return
            _run(job)


def _run(job: _Job) -> None:
    future, call = job
    if not future.set_running_or_notify_cancel():
        return
    try:
        result = call()
    except BaseException as err:  # noqa: BLE001 - handed to whoever waits, as a pool does
        future.set_exception(err)
    else:
        future.set_result(result)
