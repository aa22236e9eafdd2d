"""The ``oracle`` controller, for comparisons in simulation only (never the product): the
insertion machine driven by the simulator's TRUE wrench.

``TrueWrench`` replaces tau_x, tau_y, tau_z, shear and normal of each estimate by the gel's
true wrench on the plug in S, converted to the estimator's raw units with the nominal
calibration slopes below, so the machine's thresholds keep their meaning. The estimator
still runs on the frames for the flags (zeroing, contact). ``TRIAL_CONTROLLERS`` is the
product's table (``controller.run.CONTROLLERS``) with this entry added.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from controller.run import CONTROLLERS, Controller
from controller.tactile import TactileEstimator, TransformedSource, WrenchEstimate, WrenchSource

# Nominal slopes of the GelSight Mini's default estimator, N*m (or N) per raw unit
# (docs/EVALUATION.md, section 1: tilt about 1.5-2.1, tau_z about 0.02-0.04).
ORACLE_TILT_NM_PER_RAW = 1.8
ORACLE_TWIST_NM_PER_RAW = 0.03
ORACLE_FORCE_N_PER_RAW = 100.0


class TrueWrench:
    """The simulator's true gel wrench in place of an estimate's values (see the module
    doc), relative to the true wrench while the reference was captured. ``true_wrench_s``:
    returns the newest true (fx, fy, fz, tau_x, tau_y, tau_z) in S, N and N*m, of the gel on
    the plug."""

    def __init__(self, true_wrench_s: Callable[[], np.ndarray]) -> None:
        self._true = true_wrench_s
        self._zero = np.zeros(6)

    def __call__(self, e: WrenchEstimate) -> WrenchEstimate:
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


def _true_wrench_source(estimator: TactileEstimator, world: Any) -> WrenchSource:
    """The estimator with ``TrueWrench`` reading the newest true gel wrench of the simulated
    ``world``."""

    def newest_true_wrench() -> np.ndarray:
        world.sync()
        rows = world.truth.arrays()["gel_wrench_s"]
        return rows[-1] if len(rows) else np.zeros(6)

    return TransformedSource(estimator, TrueWrench(newest_true_wrench))


ORACLE = Controller(CONTROLLERS["dipole"].machine, _true_wrench_source, sim_only=True)

TRIAL_CONTROLLERS: Mapping[str, Controller] = {**CONTROLLERS, "oracle": ORACLE}
"""The controllers the trial tools compare: the product's and the oracle."""
