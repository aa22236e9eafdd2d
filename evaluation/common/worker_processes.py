"""Process pools whose workers leave signals to their parent, die with it, and are killed
at once when the parent stops.

* ``worker_pool(workers)``: a spawned ``ProcessPoolExecutor`` whose workers ignore SIGINT
  and SIGTERM (Ctrl-C and ``kill`` to the process group reach the parent, which decides;
  a worker's own control loop then does not catch them either, see
  ``controller.loop``) and are sent SIGKILL by the kernel when the parent dies, even by
  SIGKILL (Linux ``prctl(PR_SET_PDEATHSIG)``). The pool spawns its workers as tasks are
  submitted; ``submit`` holds both signals meanwhile (``signals_held``), so a worker starts
  with them blocked (a signal mask survives fork and exec) until its initializer ignores
  them, and the parent never stops half-way through handing a worker its start-up data:
  either would print a worker's traceback.
* ``kill_pool(pool)``: SIGKILL the workers now (their running and queued tasks are
  abandoned), then wait for them to be gone.
* ``ordered_map(pool, fn, items, window)``: ``pool.map`` that submits at most ``window``
  tasks ahead of the result it yields, so a stream of any length takes the same memory.
"""

from __future__ import annotations

import ctypes
import os
import signal
import sys
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import Future, ProcessPoolExecutor
from contextlib import contextmanager
from multiprocessing import get_context
from typing import Any, TypeVar

PR_SET_PDEATHSIG = 1  # linux/prctl.h
JOIN_TIMEOUT_S = 5.0
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)

T = TypeVar("T")


@contextmanager
def signals_held() -> Iterator[None]:
    """SIGINT and SIGTERM are blocked in this thread during the block, and the first that
    arrives is delivered to the handlers of before when it ends (main thread only)."""
    received: list[int] = []
    previous = {
        signum: signal.signal(signum, lambda got, _: received.append(got))
        for signum in STOP_SIGNALS
    }
    mask = signal.pthread_sigmask(signal.SIG_BLOCK, STOP_SIGNALS)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, mask)
        for signum, handler in previous.items():
            signal.signal(signum, handler)
        if received:
            signal.raise_signal(received[0])


class _WorkerPool(ProcessPoolExecutor):
    def submit(self, fn: Callable[..., T], /, *args: Any, **kwargs: Any) -> Future[T]:
        with signals_held():
            return super().submit(fn, *args, **kwargs)


def _leave_signals_and_die_with(parent_pid: int) -> None:
    """Pool initializer (see the module doc); exits at once if the parent is already gone."""
    for signum in STOP_SIGNALS:
        signal.signal(signum, signal.SIG_IGN)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, STOP_SIGNALS)
    if sys.platform.startswith("linux"):
        ctypes.CDLL(None, use_errno=True).prctl(PR_SET_PDEATHSIG, signal.SIGKILL)
    if os.getppid() != parent_pid:
        os._exit(1)


def worker_pool(workers: int) -> ProcessPoolExecutor:
    """A pool of ``workers`` spawned processes set up as the module doc says."""
    return _WorkerPool(
        workers,
        get_context("spawn"),
        initializer=_leave_signals_and_die_with,
        initargs=(os.getpid(),),
    )


def kill_pool(pool: ProcessPoolExecutor) -> None:
    """SIGKILL the pool's workers, waiting until they are gone; its tasks, running or
    queued, end with BrokenProcessPool. Before Python 3.14 (``kill_workers``) the processes
    are only reachable as ``_processes``, which ``shutdown`` clears: taken first. No future
    is cancelled: before Python 3.12 the pool's own thread raises InvalidStateError (a
    traceback) when it fails a cancelled future of a broken pool."""
    kill = getattr(pool, "kill_workers", None)
    if kill is not None:
        kill()
        return
    processes = list((getattr(pool, "_processes", None) or {}).values())
    for process in processes:
        process.kill()
    for process in processes:
        process.join(timeout=JOIN_TIMEOUT_S)
    pool.shutdown(wait=False)


def ordered_map(
    pool: ProcessPoolExecutor, fn: Callable[[Any], T], items: Iterable[Any], window: int
) -> Iterator[T]:
    """``fn`` of each item, in the items' order, computed by ``pool`` with at most
    ``window`` tasks submitted and not yet yielded (``pool.map`` submits every item first)."""
    if window < 1:
        raise ValueError(f"window {window}: expected at least 1")
    queued = iter(items)
    pending: deque[Future[T]] = deque()
    while True:
        for item in queued:
            pending.append(pool.submit(fn, item))
            if len(pending) >= window:
                break
        if not pending:
            return
        yield pending.popleft().result()
