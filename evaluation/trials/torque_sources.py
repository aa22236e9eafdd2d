"""What drives the insertion machine's torques, per controller of a trial (the same machine
in every case; docs/EVALUATION.md compares them on the same seeds):

* ``dipole``: the estimator as it is (dipole tilt, NHHD in-plane torque): the product;
* ``fingervision``: the same estimates with tau_x, tau_y, tau_z replaced by the FingerVision
  baseline's (``fv_tau_*``), i.e. the baseline driving the same machine;
* ``oracle``: the simulator's TRUE wrench (an upper bound, never the product): tau_x, tau_y,
  tau_z, shear and normal replaced by the gel's true wrench on the plug in S, converted to
  the estimator's raw units with the nominal calibration slopes below, so the machine's
  thresholds keep their meaning. The estimator still runs on the frames for the flags
  (zeroing, contact). Only evaluation/ builds it, only with the simulated backend.

Each source has the estimator's ``push(frame, t_s)``, ``capture_open(n)`` and
``rezero(n)``, which is all the control loop calls.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable

import numpy as np

from controller.tactile import TactileEstimator, WrenchEstimate

# Nominal slopes of the GelSight Mini's default estimator, N*m (or N) per raw unit
# (docs/EVALUATION.md, section 1: tilt about 1.5-2.1, tau_z about 0.02-0.04).
ORACLE_TILT_NM_PER_RAW = 1.8
ORACLE_TWIST_NM_PER_RAW = 0.03
ORACLE_FORCE_N_PER_RAW = 100.0


class BaselineTorques:
    """The estimator with its torques replaced by the FingerVision baseline's."""

    def __init__(self, estimator: TactileEstimator) -> None:
        self.estimator = estimator

    def capture_open(self, n_frames: int | None = None) -> None:
        self.estimator.capture_open(n_frames)

    def rezero(self, n_frames: int | None = None) -> None:
        self.estimator.rezero(n_frames)

    def push(self, frame: np.ndarray, t_s: float) -> WrenchEstimate:
        e = self.estimator.push(frame, t_s)
        return dataclasses.replace(e, tau_x=e.fv_tau_x, tau_y=e.fv_tau_y, tau_z=e.fv_tau_z)


class TrueWrench:
    """The simulator's true gel wrench in place of the estimate's values (see the module
    doc). ``true_wrench_s``: returns the newest true (fx, fy, fz, tau_x, tau_y, tau_z) in S,
    N and N*m, of the gel on the plug."""

    def __init__(
        self, estimator: TactileEstimator, true_wrench_s: Callable[[], np.ndarray]
    ) -> None:
        self.estimator = estimator
        self._true = true_wrench_s
        self._zero = np.zeros(6)

    def capture_open(self, n_frames: int | None = None) -> None:
        self.estimator.capture_open(n_frames)

    def rezero(self, n_frames: int | None = None) -> None:
        self.estimator.rezero(n_frames)

    def push(self, frame: np.ndarray, t_s: float) -> WrenchEstimate:
        e = self.estimator.push(frame, t_s)
        wrench = np.asarray(self._true(), float)
        if e.zeroing:
            self._zero = wrench.copy()
            return e
        fx, fy, fz, tx, ty, tz = wrench - self._zero
        return dataclasses.replace(
            e,
            tau_x=tx / ORACLE_TILT_NM_PER_RAW,
            tau_y=ty / ORACLE_TILT_NM_PER_RAW,
            tau_z=tz / ORACLE_TWIST_NM_PER_RAW,
            shear_x=fx / ORACLE_FORCE_N_PER_RAW,
            shear_y=fy / ORACLE_FORCE_N_PER_RAW,
            normal=fz / ORACLE_FORCE_N_PER_RAW,
        )
