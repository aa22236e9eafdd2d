"""Held-out linear calibration scores: fit on one half of a sequence, score on the other.

The fit is the calibration a user would make: truth ~ offset + gain * estimate, by least
squares on the first half of the frames. The score is on the second half, with the first
half's offset and gain: R^2 = 1 - SS_res / SS_tot (can be negative: worse than predicting
the held-out mean), and the RMSE relative to the held-out truth's range.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class HeldOutFit:
    """``gain`` and ``offset`` fitted on the first half; ``r2`` and ``rmse_rel`` (RMSE /
    range of the truth) on the second half."""

    gain: float
    offset: float
    r2: float
    rmse_rel: float


def held_out_fit(estimate: np.ndarray, truth: np.ndarray) -> HeldOutFit:
    """Fit truth ~ offset + gain * estimate on the first half, score on the second half.

    A constant estimate gets gain 0 (the fit predicts the first half's mean)."""
    estimate = np.asarray(estimate, np.float64)
    truth = np.asarray(truth, np.float64)
    if estimate.shape != truth.shape or estimate.ndim != 1 or estimate.size < 4:
        raise ValueError(
            f"estimate and truth must be equal 1-D series of at least 4 values, got "
            f"{estimate.shape} and {truth.shape}"
        )
    half = estimate.size // 2
    fit_est, fit_truth = estimate[:half], truth[:half]
    spread = fit_est - fit_est.mean()
    denominator = float(spread @ spread)
    # Relative floor: an estimate constant to rounding error carries no information.
    if denominator <= 1e-24 * max(1.0, float(fit_est @ fit_est)):
        gain = 0.0
    else:
        gain = float(spread @ (fit_truth - fit_truth.mean())) / denominator
    offset = float(fit_truth.mean() - gain * fit_est.mean())
    test_truth = truth[half:]
    residual = test_truth - (offset + gain * estimate[half:])
    total = float(((test_truth - test_truth.mean()) ** 2).sum())
    r2 = 1.0 - float(residual @ residual) / total if total > 0 else float("nan")
    span = float(np.ptp(test_truth))
    rmse = float(np.sqrt(np.mean(residual**2)))
    return HeldOutFit(gain, offset, r2, rmse / span if span > 0 else float("nan"))
