"""Where a batch's trials run: in this process, in a local process pool, or on Ray.

Every executor is a context manager whose ``run(function, specs)`` yields ``(spec,
result)`` for each spec, in the order the trials finish. A trial that raises becomes a failed
result (status ``error``, see ``evaluation.trials.guard``), so one bad seed never ends the
batch. The trials are submitted a few at a time (``WINDOW_PER_WORKER`` per worker), so
``specs`` may be a lazy sequence of any length. Leaving the context on an exception (Ctrl-C,
SIGTERM) stops the trials still running: the local pool's worker processes are killed, Ray's
tasks cancelled.

The Ray executor lives in ``evaluation.trials.ray_executor`` (Ray is an optional extra);
``open_executor`` imports it only when asked for.
"""

from __future__ import annotations

import time
from collections.abc import Iterable, Iterator
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from concurrent.futures.process import BrokenProcessPool
from itertools import islice
from types import TracebackType
from typing import Protocol

from controller.run.result import TrialResult
from evaluation.common.machine_info import one_thread_env
from evaluation.common.worker_processes import kill_pool, worker_pool
from evaluation.trials.guard import error_result, guarded
from evaluation.trials.spec import TrialFunction, TrialSpec

EXECUTORS = ("local", "ray")


class Executor(Protocol):
    """Runs trials; see the module doc."""

    name: str
    workers: int

    def __enter__(self) -> Executor: ...

    def __exit__(
        self,
        kind: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None: ...

    def run(
        self, function: TrialFunction, specs: Iterable[TrialSpec]
    ) -> Iterator[tuple[TrialSpec, TrialResult]]:
        """``(spec, result)`` per spec, as the trials finish."""
        ...


WINDOW_PER_WORKER = 2
"""Trials submitted at once per worker (running or queued): enough to keep every worker busy,
few enough that a batch of any length takes the same memory and that a stop has little to
cancel."""


class LocalExecutor:
    """``workers`` = 1: the trials run one after the other in this process; more: in a pool
    of that many worker processes (``evaluation.common.worker_processes``: spawned, one
    BLAS/OpenMP thread each, signals left to this process, killed with it)."""

    name = "local"

    def __init__(self, workers: int = 1) -> None:
        if workers < 1:
            raise ValueError(f"workers {workers}: expected at least 1")
        self.workers = workers
        self._pool: ProcessPoolExecutor | None = None

    def __enter__(self) -> LocalExecutor:
        if self.workers > 1:
            one_thread_env()
            self._pool = worker_pool(self.workers)
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        pool, self._pool = self._pool, None
        if pool is None:
            return
        if kind is None:
            pool.shutdown(wait=True)
            return
        kill_pool(pool)

    def run(
        self, function: TrialFunction, specs: Iterable[TrialSpec]
    ) -> Iterator[tuple[TrialSpec, TrialResult]]:
        if self._pool is None:
            for spec in specs:
                yield spec, guarded(function, spec)
            return
        queued = iter(specs)
        pending: dict[Future[TrialResult], TrialSpec] = {}
        began = time.perf_counter()
        while True:
            for spec in islice(queued, WINDOW_PER_WORKER * self.workers - len(pending)):
                pending[self._pool.submit(guarded, function, spec)] = spec
            if not pending:
                return
            done, _ = wait(pending, return_when=FIRST_COMPLETED)
            for future in done:
                spec = pending.pop(future)
                try:
                    result = future.result()
                except BrokenProcessPool:
                    result = error_result(
                        spec, "a worker process died", time.perf_counter() - began
                    )
                yield spec, result


def open_executor(name: str, workers: int = 1, address: str | None = None) -> Executor:
    """The executor called ``name`` (one of ``EXECUTORS``); ``address`` is the Ray cluster
    to join (None: start a local Ray instance with ``workers`` CPUs)."""
    if name == "local":
        if address is not None:
            raise ValueError("a Ray address is given but the executor is local")
        return LocalExecutor(workers)
    if name == "ray":
        from evaluation.trials.ray_executor import RayExecutor

        return RayExecutor(workers, address, WINDOW_PER_WORKER)
    raise ValueError(f"executor {name!r}: expected one of {', '.join(EXECUTORS)}")
