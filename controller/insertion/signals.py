"""The machine's tactile signals: the estimate relative to a per-run baseline, in noise units,
filtered.

After each re-zero, the first ``baseline_frames`` estimates (contact-free: the plug is in
the air) give each channel c of (tau_x, tau_y, tau_z, shear_x, shear_y, normal) its mean
m_c and noise s_c = max(std_c, floor_c). Every later estimate v gives the normalised
deviation n_c = (v_c - m_c) / s_c, filtered by an exponential moving average
f <- alpha n + (1 - alpha) f, once per new estimate (the machine ticks faster than the
camera; a repeated estimate is not a new sample). Signals in T use the rotation R_S2T.
"""

from __future__ import annotations

import numpy as np

from controller.insertion.machine_config import SignalSettings, s2t_matrix
from controller.tactile.wrench import WrenchEstimate

CHANNELS = ("tau_x", "tau_y", "tau_z", "shear_x", "shear_y", "normal")


class TactileSignals:
    """Baseline, normalisation and filtering of the tactile estimate (see the module doc).

    ``reset()`` after asking for a re-zero: estimates are then ignored until one flagged
    ``zeroing`` has been seen (so a stale pre-zero estimate never enters the baseline), and
    the baseline is measured again from the first estimates after zeroing."""

    def __init__(self, settings: SignalSettings) -> None:
        self._settings = settings
        floor = settings.noise_floor
        self._floor = np.array(
            [floor.tilt_x, floor.tilt_y, floor.inplane, floor.shear_x, floor.shear_y, floor.normal]
        )
        self.s2t = s2t_matrix(settings.torque_axes)
        self._armed = True
        self._last_t_s: float | None = None
        self._samples: list[np.ndarray] = []
        self._mean: np.ndarray | None = None
        self._sigma: np.ndarray | None = None
        self._filtered = np.zeros(len(CHANNELS))

    def reset(self) -> None:
        """Forget the baseline; wait for the next zeroing to end before measuring it again."""
        self._armed = False
        self._samples = []
        self._mean = None
        self._sigma = None
        self._filtered = np.zeros(len(CHANNELS))

    def update(self, estimate: WrenchEstimate | None) -> bool:
        """Take ``estimate``; True if it was a new sample that updated the filtered signals."""
        if estimate is None or estimate.t_s == self._last_t_s:
            return False
        self._last_t_s = estimate.t_s
        if estimate.zeroing:
            self._armed = True
            return False
        if not self._armed:
            return False
        values = np.array([getattr(estimate, name) for name in CHANNELS], dtype=float)
        if self._mean is None:
            self._samples.append(values)
            if len(self._samples) >= self._settings.baseline_frames:
                stacked = np.stack(self._samples)
                self._mean = stacked.mean(axis=0)
                self._sigma = np.maximum(stacked.std(axis=0), self._floor)
                self._filtered = np.zeros(len(CHANNELS))
            return False
        normalised = (values - self._mean) / self._sigma
        alpha = self._settings.ema_alpha
        self._filtered = alpha * normalised + (1.0 - alpha) * self._filtered
        return True

    @property
    def ready(self) -> bool:
        """True once the baseline has been measured."""
        return self._mean is not None

    @property
    def normalised(self) -> np.ndarray:
        """Filtered normalised deviations of the six channels (noise units), zero before the
        baseline is ready."""
        return self._filtered.copy()

    @property
    def magnitude(self) -> float:
        """Euclidean norm of the six filtered normalised deviations (noise units)."""
        return float(np.linalg.norm(self._filtered))

    @property
    def torque_t(self) -> np.ndarray:
        """The filtered normalised torques (tau_x, tau_y, tau_z of S) as a vector in T."""
        return self.s2t @ self._filtered[:3]

    @property
    def deviation(self) -> np.ndarray:
        """Filtered deviations from the baseline in the estimate's units (N*m, N when
        calibrated; six channels)."""
        if self._sigma is None:
            return np.zeros(len(CHANNELS))
        return self._filtered * self._sigma

    @property
    def axial_force_sigma(self) -> float:
        """The filtered force along T z in noise units: the normalised force channels
        (shear_x, shear_y, normal of S) rotated into T (see ``axial_force`` for the same in
        the estimate's units). The load SEARCH, ALIGN and INSERT hold and judge."""
        return float((self.s2t @ self._filtered[3:])[2])

    @property
    def axial_force(self) -> float:
        """The filtered force along T z (toward the plug's tip), in the estimate's units (N
        when calibrated): the force
        vector (shear_x, shear_y, normal) of S, relative to its baseline, rotated into T.
        Positive when the board pushes the plug into the grasp."""
        return float((self.s2t @ self.deviation[3:])[2])
