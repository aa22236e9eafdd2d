"""Tactile dipole moment and the tilt torque it gives (Fuchioka & Hamaya, ICRA 2024).

Given the divergence ``div_i`` of the zeroed displacement field at grid points ``x_i`` (frame S,
mm), with N points:

1. C+ is the centroid of the points with div > 0, weighted by div; C- likewise for div < 0,
   weighted by |div|.
2. m = (C+ + C-) / 2 and r_i = x_i - m (origin ``centroid_midpoint``), or r_i = x_i
   (origin ``sensor_centre``, the gel centre).
3. p = (1/N) sum_i r_i div_i, in mm.
4. tilt torque tau = [c_x p_y, -c_y p_x]; with c = 1 this is the raw torque in mm.

Sign: pressure rising toward +y makes the gel spread there (div > 0 at +y, < 0 at -y), so
p_y > 0 and tau_x > 0: the torque about S's x axis that the gel exerts on the grasped object
(docs/ARCHITECTURE.md has the drawing).

Unlike the authors' code, nothing here divides by the centroid distance, so an empty field
gives zero torque and the ``degenerate`` flag, never NaN.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import numpy as np

from controller.tactile.field import require_finite

DipoleOrigin = Literal["centroid_midpoint", "sensor_centre"]

# A sign region whose |div| mass is below this fraction of the total counts as absent.
_EMPTY_REGION_FRACTION = 1e-9


@dataclass(frozen=True)
class DipoleMoment:
    """The dipole moment ``p`` (mm), the origin ``m`` it was taken about (mm, frame S), and
    ``degenerate``: the field had no positive or no negative divergence (p is then zero)."""

    p_x: float
    p_y: float
    m_x: float
    m_y: float
    degenerate: bool

    @property
    def tilt_torque_raw(self) -> tuple[float, float]:
        """(tau_x, tau_y) with c_x = c_y = 1, in mm: [p_y, -p_x]."""
        return self.p_y, -self.p_x


class DipoleMomentCalculator:
    """Computes the dipole moment on a fixed grid without allocating per call.

    ``x_mm`` (cols,) and ``y_mm`` (rows,) are the grid's cell centres in frame S.
    """

    def __init__(
        self, x_mm: np.ndarray, y_mm: np.ndarray, origin: DipoleOrigin = "centroid_midpoint"
    ) -> None:
        if origin not in ("centroid_midpoint", "sensor_centre"):
            raise ValueError(
                f"dipole origin must be 'centroid_midpoint' or 'sensor_centre', got {origin!r}"
            )
        self.origin = origin
        grid_x, grid_y = np.meshgrid(x_mm, y_mm)
        self._x = grid_x.ravel()
        self._y = grid_y.ravel()
        self._positive = np.empty_like(self._x)
        self._negative = np.empty_like(self._x)

    def __call__(self, div: np.ndarray) -> DipoleMoment:
        """Dipole moment of ``div`` (rows, cols), dimensionless divergence of the field."""
        flat = div.reshape(-1)
        if flat.shape != self._x.shape:
            raise ValueError(
                f"divergence must have {self._x.size} grid values, got shape {div.shape}"
            )
        require_finite("divergence", flat)
        n = flat.size
        np.maximum(flat, 0.0, out=self._positive)
        np.minimum(flat, 0.0, out=self._negative)
        mass_pos = float(self._positive.sum())
        mass_neg = -float(self._negative.sum())
        moment_x = float(self._x @ flat)
        moment_y = float(self._y @ flat)

        if self.origin == "sensor_centre":
            degenerate = mass_pos + mass_neg == 0.0
            return DipoleMoment(moment_x / n, moment_y / n, 0.0, 0.0, degenerate)

        floor = _EMPTY_REGION_FRACTION * (mass_pos + mass_neg)
        if mass_pos <= floor or mass_neg <= floor or mass_pos + mass_neg == 0.0:
            return DipoleMoment(0.0, 0.0, 0.0, 0.0, True)
        c_pos_x = float(self._x @ self._positive) / mass_pos
        c_pos_y = float(self._y @ self._positive) / mass_pos
        c_neg_x = -float(self._x @ self._negative) / mass_neg
        c_neg_y = -float(self._y @ self._negative) / mass_neg
        m_x = 0.5 * (c_pos_x + c_neg_x)
        m_y = 0.5 * (c_pos_y + c_neg_y)
        net = mass_pos - mass_neg
        # sum_i (x_i - m) div_i = sum_i x_i div_i - m * sum_i div_i
        p_x = (moment_x - m_x * net) / n
        p_y = (moment_y - m_y * net) / n
        return DipoleMoment(p_x, p_y, m_x, m_y, False)
