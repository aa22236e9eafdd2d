"""Trials on Ray: a local Ray instance, or a cluster joined by address (optional extra).

    pip install 'tactile-insertion[ray]'

Each trial is one Ray task of one CPU running ``guard.guarded``, so a trial's exception
is a failed result exactly as with the local executor, and the batch's summary is the same
for the same seeds. The tasks are submitted a few at a time (``window_per_cpu`` per CPU of
the instance or cluster), so a batch of any length takes the same memory. The trial
function and this package must be importable on the workers (on a cluster: the same
installation on every node, or a ``runtime_env``).
"""

from __future__ import annotations

import logging
import socket
import time
from collections.abc import Iterable, Iterator
from itertools import islice
from types import TracebackType
from typing import Any

from controller.cli.support import ToolError, one_line
from controller.run.result import TrialResult
from evaluation.trials.guard import error_result, guarded
from evaluation.trials.spec import TrialFunction, TrialSpec


class RayNotInstalled(ToolError, ImportError):
    """Ray is missing: the message says which extra to install."""


try:
    import ray
except ImportError:
    raise RayNotInstalled(
        "the Ray executor needs Ray, which is not installed; "
        "install the extra: pip install 'tactile-insertion[ray]'"
    ) from None


CONNECT_TIMEOUT_S = 5.0


def check_reachable(address: str) -> None:
    """Refuse a ``[ray://]HOST:PORT`` address that does not accept a TCP connection within
    ``CONNECT_TIMEOUT_S`` (Ray itself would retry for minutes); ``auto`` is left to Ray."""
    host, sep, port = address.removeprefix("ray://").rpartition(":")
    if not sep or not port.isdigit():
        if address == "auto":
            return
        raise ToolError(f"--ray-address {address!r}: expected auto, HOST:PORT or ray://HOST:PORT")
    try:
        socket.create_connection((host, int(port)), timeout=CONNECT_TIMEOUT_S).close()
    except OSError as exc:
        reason = exc.strerror or type(exc).__name__
        raise ToolError(f"--ray-address {address}: cannot connect ({reason})") from None


class RayExecutor:
    """Runs trials as Ray tasks. ``address`` None starts a local Ray instance with
    ``workers`` CPUs (shut down on exit); an address (``auto``, ``ray://host:10001``) joins
    that cluster, whose own CPUs set the parallelism (disconnected on exit). At most
    ``window_per_cpu`` tasks per CPU are submitted at once (``open_executor`` passes the
    local executor's ``WINDOW_PER_WORKER``)."""

    name = "ray"

    def __init__(
        self, workers: int = 1, address: str | None = None, window_per_cpu: int = 2
    ) -> None:
        if workers < 1:
            raise ValueError(f"workers {workers}: expected at least 1")
        self.workers = workers
        self.address = address
        self.window_per_cpu = window_per_cpu
        self._pending: list[Any] = []

    def __enter__(self) -> RayExecutor:
        options: dict[str, Any] = {"logging_level": logging.WARNING, "include_dashboard": False}
        try:
            if self.address is None:
                ray.init(num_cpus=self.workers, **options)
            else:
                check_reachable(self.address)
                ray.init(address=self.address, **options)
        except (ConnectionError, ValueError, RuntimeError) as exc:
            where = self.address or "a local instance"
            raise ToolError(
                f"--ray-address: cannot start or join Ray at {where} ({one_line(exc)})"
            ) from None
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        pending, self._pending = self._pending, []
        try:
            for ref in pending:
                ray.cancel(ref, force=True)
        finally:
            ray.shutdown()

    def run(
        self, function: TrialFunction, specs: Iterable[TrialSpec]
    ) -> Iterator[tuple[TrialSpec, TrialResult]]:
        task = ray.remote(num_cpus=1, max_retries=0)(guarded)
        cpus = max(self.workers, int(ray.cluster_resources().get("CPU", 1)))
        window = self.window_per_cpu * cpus
        queued = iter(specs)
        by_ref: dict[Any, TrialSpec] = {}
        began = time.perf_counter()
        while True:
            for spec in islice(queued, window - len(self._pending)):
                ref = task.remote(function, spec)
                by_ref[ref] = spec
                self._pending.append(ref)
            if not self._pending:
                return
            done, self._pending = ray.wait(self._pending, num_returns=1)
            for ref in done:
                spec = by_ref.pop(ref)
                try:
                    result = ray.get(ref)
                except ray.exceptions.RayError as exc:  # a worker died, a task was lost
                    first = (str(exc).splitlines() or [""])[0]
                    result = error_result(
                        spec, f"{type(exc).__name__}: {first}", time.perf_counter() - began
                    )
                yield spec, result
