"""What the control loop reads the wrench from (controller/loop.py): the tactile estimator,
or the estimator with part of each estimate replaced (``TransformedSource``: the
FingerVision baseline's torques, controller/run/controllers.py; the simulator's true wrench,
evaluation/trials/oracle.py)."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol, runtime_checkable

import numpy as np

from controller.tactile.estimator import TactileEstimator
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


class TransformedSource:
    """A WrenchSource that runs ``estimator`` on every frame and hands each estimate through
    ``transform`` (e.g. replacing the torques by another method's); the captures of the open
    gel and of the reference are the estimator's."""

    def __init__(
        self, estimator: WrenchSource, transform: Callable[[WrenchEstimate], WrenchEstimate]
    ) -> None:
        self.estimator = estimator
        self.transform = transform

    def push(self, frame: np.ndarray, t_s: float) -> WrenchEstimate:
        return self.transform(self.estimator.push(frame, t_s))

    def capture_open(self, n_frames: int | None = None) -> None:
        self.estimator.capture_open(n_frames)

    def rezero(self, n_frames: int | None = None) -> None:
        self.estimator.rezero(n_frames)


def estimator_of(source: Any) -> TactileEstimator | None:
    """The ``TactileEstimator`` at the bottom of ``source`` (through wrappers' ``.estimator``,
    as ``TransformedSource``), None if there is none."""
    while not isinstance(source, TactileEstimator):
        source = getattr(source, "estimator", None)
        if source is None:
            return None
    return source
