"""What the live view draws: one ``ViewSnapshot`` per tactile frame (numpy arrays and
plain values only, so the view's process unpickles it without loading the controller)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ViewSnapshot:
    """One frame of the view. ``t_s``: the frame's capture time (s, loop clock);
    ``image``: uint8 BGR (rows, cols, 3) or None; ``x_mm``, ``y_mm``, ``u_mm``, ``v_mm``,
    ``div``: the displacement field on its grid in S (mm; div dimensionless), or None
    before the reference; ``tau``: (tau_x, tau_y, tau_z) of the estimate (raw mm, mm^2, or
    N*m when ``calibrated``; NaN where not finite); ``phase``: the machine's phase;
    ``operator``: the operator in control; ``connected``, ``deadman``, ``estop``: the pad;
    ``mm_per_px``: the image's scale."""

    t_s: float
    image: np.ndarray | None
    x_mm: np.ndarray | None
    y_mm: np.ndarray | None
    u_mm: np.ndarray | None
    v_mm: np.ndarray | None
    div: np.ndarray | None
    tau: tuple[float, float, float]
    calibrated: bool
    phase: str
    operator: bool
    connected: bool
    deadman: bool
    estop: bool
    mm_per_px: float
