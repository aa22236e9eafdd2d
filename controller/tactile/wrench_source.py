"""What the control loop reads the wrench from (controller/loop.py): the tactile estimator,
or an evaluation's stand-in that wraps it (evaluation/trials/torque_sources.py)."""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from controller.tactile.wrench import WrenchEstimate


@runtime_checkable
class WrenchSource(Protocol):
    """Turns tactile frames into wrench estimates; ``TactileEstimator`` is one."""

    def push(self, frame: np.ndarray, t_s: float) -> WrenchEstimate:
        """The estimate from one camera frame (uint8 H x W grey, BGR or BGRA) captured at
        ``t_s`` seconds on the loop's clock. Torques are about the sensor frame S's axes
        (tau_x, tau_y: tilt; tau_z: in-plane), in the estimator's raw units (mm-based) unless
        the estimate is ``calibrated`` (N*m, N); while a reference or the open gel is being
        captured the estimate is zero and flagged ``zeroing``."""
        ...

    def capture_open(self, n_frames: int | None = None) -> None:
        """Take the next ``n_frames`` pushed frames (None: the source's default) as the open
        gel (gripper open, nothing touching); the estimates stay ``zeroing`` until
        ``rezero`` has captured a reference."""
        ...

    def rezero(self, n_frames: int | None = None) -> None:
        """Take the mean of the next ``n_frames`` pushed frames (None: the source's default)
        as the zero-wrench reference."""
        ...
