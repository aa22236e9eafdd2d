"""FEEL's estimate of the plug in the hand, scored against the scene's truth per trial
(``TrialResult``'s pose fields, evaluation/trials/grasp_truth.py): the summary's block and
the errors charts.py histograms.

Errors are absolute: the width-plane tilt in degrees, the tip's offset along T x in mm.
The thickness-plane tilt and the tip's offset along T y are not estimated (FEEL leaves them
nominal), so their error is the truth itself, given beside for scale.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np

from controller.run.result import TrialResult


def _stats(values: Sequence[float], scale: float) -> dict[str, float] | None:
    if not values:
        return None
    v = np.abs(np.asarray(values, float)) * scale
    return {
        "median": float(np.median(v)),
        "p95": float(np.percentile(v, 95)),
        "max": float(v.max()),
    }


def _estimated(results: Iterable[TrialResult]) -> list[TrialResult]:
    return [r for r in results if math.isfinite(r.grasp_tilt_est_rad)]


def tilt_errors_deg(results: Iterable[TrialResult]) -> list[float]:
    """|estimated - true| width-plane tilt (deg) of each trial with an estimate."""
    return [
        math.degrees(abs(r.grasp_tilt_est_rad - r.grasp_tilt_true_rad)) for r in _estimated(results)
    ]


def tip_errors_mm(results: Iterable[TrialResult]) -> list[float]:
    """|estimated - true| tip offset along T x (mm) of each trial with an estimate."""
    return [1e3 * abs(r.tip_x_est_m - r.tip_x_true_m) for r in _estimated(results)]


def grasp_estimate_summary(results: Sequence[TrialResult]) -> dict[str, Any] | None:
    """The summary's ``grasp_estimate`` block: how many trials have an estimate, and the
    errors' median, 95th percentile and largest (tilt in deg, tip in mm), with the
    unestimated thickness-plane tilt and tip offset along T y for scale; None when no trial
    has one (a controller without FEEL)."""
    estimated = _estimated(results)
    if not estimated:
        return None
    with_truth = [r for r in results if math.isfinite(r.grasp_tilt_true_rad)]
    return {
        "estimated": len(estimated),
        "of": len(results),
        "tilt_error_deg": _stats(tilt_errors_deg(estimated), 1.0),
        "tip_x_error_mm": _stats(tip_errors_mm(estimated), 1.0),
        "thickness_tilt_deg_not_estimated": _stats(
            [r.grasp_tilt_thickness_true_rad for r in with_truth], math.degrees(1.0)
        ),
        "tip_y_mm_not_estimated": _stats([r.tip_y_true_m for r in with_truth], 1e3),
    }
