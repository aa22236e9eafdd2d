"""A trial that raises becomes an error result, so one bad seed never ends a batch: the
guard every executor (``executors``, ``ray_executor``) runs each trial through."""

from __future__ import annotations

import math
import time

from controller.cli.support import one_line
from controller.run.result import TrialResult
from evaluation.trials.spec import TrialFunction, TrialSpec


def error_result(spec: TrialSpec, reason: str, wall_time_s: float) -> TrialResult:
    """The result of a trial that did not run to an outcome: status ``error``, failed with
    ``"error: ..."``, no simulated time, no force measured (0 N) and an unknown force limit
    (NaN)."""
    return TrialResult(
        task=spec.task,
        controller=spec.controller,
        seed=spec.seed,
        success=False,
        status="error",
        failure_reason=f"error: {one_line(reason)}",
        time_to_insert_s=None,
        duration_s=0.0,
        max_wrist_force_n=0.0,
        force_limit_n=math.nan,
        wall_time_s=wall_time_s,
    )


def guarded(function: TrialFunction, spec: TrialSpec) -> TrialResult:
    """``function(spec)``, with an exception turned into an error result naming its type
    and message (module-level: the worker processes and Ray import it by name)."""
    began = time.perf_counter()
    try:
        return function(spec)
    except Exception as exc:  # noqa: BLE001 -- any trial failure is a result, not a crash
        return error_result(spec, f"{type(exc).__name__}: {exc}", time.perf_counter() - began)
