"""A batch's summary: success rate with its Wilson interval, times, forces, failures, speed.

``summarize`` depends only on the set of results (not on the order they arrived in), so the
same seeds give the same summary on every executor.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Iterable
from typing import Any

import numpy as np
from scipy.stats import binomtest

from controller.run.result import TrialResult
from evaluation.trials.grasp_scores import grasp_estimate_summary

CONFIDENCE = 0.95


def wilson_ci(successes: int, n: int, confidence: float = CONFIDENCE) -> tuple[float, float] | None:
    """The Wilson score interval of a success rate (no continuity correction); None for
    ``n`` = 0."""
    if n == 0:
        return None
    interval = binomtest(successes, n).proportion_ci(confidence_level=confidence, method="wilson")
    return float(interval.low), float(interval.high)


def _finite_or_none(value: float) -> float | None:
    return float(value) if math.isfinite(value) else None


def _finite_median(values: Iterable[float]) -> float | None:
    """The median of the finite ``values``, None with none."""
    finite = [v for v in values if math.isfinite(v)]
    return float(np.median(finite)) if finite else None


def quantile_over_all(times_s: Iterable[float], n: int, q: float) -> float | None:
    """The ``q`` quantile (0..1, linear interpolation as NumPy's default) of the time to
    insert over ``n`` trials of which ``times_s`` are the successes' (s): a failure counts as
    never, so None when the quantile reaches one (more than ``1 - q`` of the trials failed)."""
    ordered = sorted(times_s)
    if n == 0:
        return None
    position = q * (n - 1)
    low, high = math.floor(position), math.ceil(position)
    if high >= len(ordered):
        return None
    return ordered[low] + (ordered[high] - ordered[low]) * (position - low)


def summarize(results: Iterable[TrialResult], **context: Any) -> dict[str, Any]:
    """The batch summary of ``results`` (see docs: keys and meanings), with the keyword ``context``
    (task, controller, seeds, overrides, executor, workers, ...) merged in first.

    Times are simulated seconds from the controller's start to the depth
    (``TrialResult.time_to_insert_s``), over the successful trials (``median_time_s``,
    ``p90_time_s``) and over every trial with a failure counted as never (``median_time_all_s``,
    ``p90_time_all_s``: None where the quantile reaches a failure); ``max_wrist_force_n`` is
    over every trial; a trial is over force when its ``max_wrist_force_n`` exceeds its own
    ``force_limit_n``; the plug's true contact force: ``max_contact_force_n`` (over every
    trial), ``p99_contact_force_n`` (the largest of the trials' 99th percentiles), the same of
    the insertion force (``max_insertion_force_n``, ``p99_insertion_force_n``), its limit
    ``contact_force_limit_n``, ``insertion_force_violations`` (summed) and
    ``insertion_force_violation_trials`` (trials with at least one); the walls' torques on the
    plug as it went in (``entry_tilt_torque_median_nm``, ``entry_inplane_torque_median_nm``:
    medians of the trials' RMS, N*m, over the trials whose tip entered; None with none:
    evaluation/trials/entry_torque.py); ``sim_speed_x_realtime`` is
    the simulated time over the wall time of the trials that ran to an outcome (error trials
    have no simulated time); ``grasp_estimate`` (only when some trial has one): FEEL's errors on
    the plug in the hand, per quantity estimated in either plane, and the true size of those not
    estimated (evaluation/trials/grasp_scores.py).
    """
    ordered = sorted(results, key=lambda r: (r.controller, r.seed))
    n = len(ordered)
    successes = sum(r.success for r in ordered)
    times = [r.time_to_insert_s for r in ordered if r.success and r.time_to_insert_s is not None]
    failed = [r for r in ordered if not r.success]
    ran = [r for r in ordered if r.status != "error"]
    wall_s = sum(r.wall_time_s for r in ran)
    limits = sorted({r.force_limit_n for r in ran if math.isfinite(r.force_limit_n)})
    contact_limits = sorted(
        {r.contact_force_limit_n for r in ran if math.isfinite(r.contact_force_limit_n)}
    )
    summary = dict(context)
    summary.update(
        n=n,
        successes=successes,
        success_rate=successes / n if n else None,
        success_ci95=wilson_ci(successes, n),
        median_time_s=float(np.median(times)) if times else None,
        p90_time_s=float(np.percentile(times, 90)) if times else None,
        median_time_all_s=quantile_over_all(times, n, 0.5),
        p90_time_all_s=quantile_over_all(times, n, 0.9),
        max_wrist_force_n=max((r.max_wrist_force_n for r in ordered), default=None),
        force_limit_n=limits[0] if len(limits) == 1 else limits or None,
        over_force_trials=sum(r.max_wrist_force_n > r.force_limit_n for r in ordered),
        max_contact_force_n=max((r.max_contact_force_n for r in ran), default=None),
        p99_contact_force_n=max((r.p99_contact_force_n for r in ran), default=None),
        max_insertion_force_n=max((r.max_insertion_force_n for r in ran), default=None),
        p99_insertion_force_n=max((r.p99_insertion_force_n for r in ran), default=None),
        contact_force_limit_n=contact_limits[0]
        if len(contact_limits) == 1
        else contact_limits or None,
        insertion_force_violations=sum(r.insertion_force_violations for r in ordered),
        insertion_force_violation_trials=sum(r.insertion_force_violations > 0 for r in ordered),
        entry_tilt_torque_median_nm=_finite_median(r.entry_tilt_torque_rms_nm for r in ran),
        entry_inplane_torque_median_nm=_finite_median(r.entry_inplane_torque_rms_nm for r in ran),
        failures=dict(sorted(Counter(r.failure_reason or "unknown" for r in failed).items())),
        failed_seeds=sorted({r.seed for r in failed}),
        errors=sum(r.status == "error" for r in ordered),
        sim_duration_s=sum(r.duration_s for r in ran),
        wall_time_s=wall_s,
        sim_speed_x_realtime=_finite_or_none(sum(r.duration_s for r in ran) / wall_s)
        if wall_s > 0
        else None,
    )
    grasp = grasp_estimate_summary(ordered)
    if grasp is not None:
        summary["grasp_estimate"] = grasp
    return summary
