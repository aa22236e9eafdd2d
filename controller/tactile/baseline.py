"""FingerVision-style torque baseline (Yamaguchi & Atkeson, 2016), as compared in the paper.

Each grid point i at lever l_i = (x_i, y_i, 0) from the image centre (frame S, mm) carries a
force f_i = [c_x u_i, c_y v_i, c_z |v_i|]; the torque is tau = (1/N) sum_i l_i x f_i. With all
c = 1 the raw torque (mm^2) is

    tau_x = mean(y |v|),  tau_y = -mean(x |v|),  tau_z = mean(x v - y u).

Per-axis calibration then fits one scale per torque axis, which absorbs c_z (tilt) and, for
an isotropic gel where c_x = c_y, the in-plane constant.
"""

from __future__ import annotations

import numpy as np

from controller.tactile.field import require_finite


class FingerVisionTorque:
    """Raw FingerVision torque on a fixed grid; allocates nothing per call."""

    def __init__(self, x_mm: np.ndarray, y_mm: np.ndarray) -> None:
        self._x, self._y = np.meshgrid(x_mm, y_mm)
        self._magnitude = np.empty(self._x.shape)

    def __call__(self, u: np.ndarray, v: np.ndarray) -> tuple[float, float, float]:
        """(tau_x, tau_y, tau_z) in mm^2 for the field (u, v), each (rows, cols) in mm."""
        if u.shape != self._x.shape or v.shape != self._x.shape:
            raise ValueError(
                f"field components must have shape {self._x.shape}, got {u.shape} and {v.shape}"
            )
        require_finite("displacement field", u, v)
        n = u.size
        np.hypot(u, v, out=self._magnitude)
        tau_x = float(np.vdot(self._y, self._magnitude)) / n
        tau_y = -float(np.vdot(self._x, self._magnitude)) / n
        tau_z = (float(np.vdot(self._x, v)) - float(np.vdot(self._y, u))) / n
        return tau_x, tau_y, tau_z
