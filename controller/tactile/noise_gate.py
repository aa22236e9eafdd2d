"""The no-contact gate: is the zeroed field's divergence more than camera noise?

Zeroed on the open gel, the field before contact is camera noise alone, and so is the tilt
the dipole reads from it. On a markerless gel that noise is not small: with 2 grey levels on
smooth LED shading the tilt moved by 4-17% of a 0.5 px tilt's peak (seeds 0-5,
docs/BENCHMARKS.md), near the images' information limit for any linear estimate
(docs/ARCHITECTURE.md, "Quiet before contact"). What tells a contact from noise is not the
tilt's size but whether the field differs from noise at all.

The divergence ``d`` (k grid values) the dipole sees is linear in the field, so under noise
alone it is Gaussian with zero mean and the covariance ``C = M Sigma M^T`` (``Sigma`` the
field's, from the flow: ``GridLKFlow.noise_covariance``; ``M`` the linear map from the field
to ``d``). Its squared Mahalanobis distance ``chi2 = d^T C^+ d`` is then chi-square with
r = rank(C) degrees of freedom: the likelihood-ratio statistic of "the field is noise"
against "it is not". The gate is

    g = smoothstep((chi2 - q) / q),   q = the chi-square quantile that noise alone exceeds
                                          with probability ``false_alarm``,

0 below q, 1 from 2 q on, continuous with a bounded slope between. The dipole takes
``g d``: the tilt of a field the test cannot tell from noise is exactly zero (flagged
``degenerate``), and any contact whose field is clearly above the noise passes unchanged
(a grasp's press is hundreds of q). The centroid-midpoint rule is homogeneous in ``d``, so
this scales the tilt by g.

Once a contact is established (the statistic above q on ``CONTACT_FRAMES`` frames in a row,
or the gate fully open once), the gate stays open until the next reference
(``NoiseGate.until_contact``): zeroed on a grasp, a tilt passing through zero is not a
return to noise, and gating it would cut a dead band into the tilt
(docs/ARCHITECTURE.md, "Quiet before contact"). Under noise alone a run of three frames above
q has a probability of about 1e-6 per frame.
"""

from __future__ import annotations

import numpy as np
from scipy.stats import chi2

# Eigenvalues of C below this fraction of the largest are directions noise does not reach
# (C is rank-deficient: the curl-free projection and the grid's borders tie values).
_RANK_TOLERANCE = 1e-9
# Frames in a row on which the field must differ from noise (statistic above the threshold)
# before a contact counts as established (NoiseGate.until_contact).
CONTACT_FRAMES = 3


class NoiseGate:
    """g(d) of the module docstring for the covariance ``covariance`` (k, k) of ``d`` under
    noise alone and the per-frame ``false_alarm`` probability in (0, 1)."""

    def __init__(self, covariance: np.ndarray, false_alarm: float) -> None:
        if not 0.0 < false_alarm < 1.0:
            raise ValueError(f"false_alarm must be in (0, 1), got {false_alarm!r}")
        covariance = np.asarray(covariance, float)
        values, vectors = np.linalg.eigh(0.5 * (covariance + covariance.T))
        keep = values > _RANK_TOLERANCE * max(float(values[-1]), 0.0)
        if not keep.any():
            raise ValueError("the noise covariance is zero: no gate can be formed")
        self.rank = int(keep.sum())
        self._whiten = vectors[:, keep] / np.sqrt(values[keep])
        self.threshold = float(chi2.isf(false_alarm, self.rank))
        self._z = np.empty(self.rank)
        self.contact = False  # until_contact's latch
        self._run = 0
        self.peak = 0.0

    def statistic(self, div: np.ndarray) -> float:
        """chi2 = d^T C^+ d of ``div`` (any shape with k values)."""
        np.dot(div.reshape(-1), self._whiten, out=self._z)
        return float(self._z @ self._z)

    def __call__(self, div: np.ndarray) -> float:
        """The gate g in [0, 1] for ``div``."""
        return self._gate(self.statistic(div))

    def until_contact(self, div: np.ndarray) -> float:
        """The gate for one frame of a sequence, until a contact is established: once the
        statistic has passed ``threshold`` on ``CONTACT_FRAMES`` frames in a row, or the gate
        has opened fully, it stays open (1) for the rest of the sequence (the estimator
        forms a gate per reference). ``peak`` keeps the largest statistic seen, relative to
        the threshold."""
        statistic = self.statistic(div)
        self.peak = max(self.peak, statistic / self.threshold)
        if self.contact:
            return 1.0
        self._run = self._run + 1 if statistic >= self.threshold else 0
        gate = self._gate(statistic)
        self.contact = gate >= 1.0 or self._run >= CONTACT_FRAMES
        return 1.0 if self.contact else gate

    def _gate(self, statistic: float) -> float:
        t = (statistic - self.threshold) / self.threshold
        if t <= 0.0:
            return 0.0
        if t >= 1.0:
            return 1.0
        return t * t * (3.0 - 2.0 * t)
