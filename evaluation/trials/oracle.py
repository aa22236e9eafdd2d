"""The ``oracle`` controller, for comparisons in simulation only (never the product): the
product's machine (``CONTROLLERS["dipole"].machine``: the press spiral by touch) driven by
the simulator's TRUE gel wrench, as the sensor would report it if the estimator were exact.

``TrueWrench`` replaces tau_x, tau_y, tau_z, shear_x, shear_y and normal of each estimate by
the true wrench the sensing gel exerts on the plug, in S, at the estimate's frame time (the
wrench the frame was rendered from), relative to the true wrench when the reference was
taken (the estimate's zero), in the calibrated units the machine reads (N*m, N) -- plus
Gaussian noise of each axis's calibrated noise at rest, as measured in the task's scene
calibration (``AxisFit.rest_std``, configs/calibrations/). It then goes through the same
path as the estimate: the same frames and times, the same reading of the plug's axial
force (the task's ``touch_spiral.axial_weights``) and the same machine. The estimator still
runs on the frames for the flags (zeroing, contact, slip).

What it is: the machine with a perfectly linear, perfectly scaled, sensor-noise-limited
wrench. What it is not: an upper bound by construction. The machine's settings (the axial
map's weights among them) were fitted and tuned on the estimate; a better signal can still
trip them differently, so whether the oracle does at least as well as the estimate is a
measurement (docs/TRIALS.md), not a given.

``TRIAL_CONTROLLERS`` is the product's table (``controller.run.CONTROLLERS``) with this entry
added.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from controller.run import CONTROLLERS, Controller
from controller.tactile import TactileEstimator, TransformedSource, WrenchEstimate, WrenchSource
from controller.tactile.calibration import Calibration
from core.config import ConfigError

TRUE_AXES = ("shear_x", "shear_y", "normal", "tau_x", "tau_y", "tau_z")
"""The estimate's fields in the order of the true (fx, fy, fz, tau_x, tau_y, tau_z) wrench."""


class TrueWrench:
    """The true gel wrench with the sensor's noise in place of an estimate's values (see the
    module doc). ``true_wrench_s(t_s)``: the true (fx, fy, fz, tau_x, tau_y, tau_z) in S, N
    and N*m, of the gel on the plug at ``t_s``; ``noise_std`` (6,): the noise added to each,
    same order and units; ``rng``: the noise's generator."""

    def __init__(
        self,
        true_wrench_s: Callable[[float], np.ndarray],
        noise_std: np.ndarray,
        rng: np.random.Generator,
    ) -> None:
        self._true = true_wrench_s
        self._noise_std = np.asarray(noise_std, float)
        if self._noise_std.shape != (6,) or not (self._noise_std >= 0).all():
            raise ValueError(f"noise_std: expected 6 non-negative numbers, got {noise_std!r}")
        self._rng = rng
        self._zero = np.zeros(6)

    def __call__(self, e: WrenchEstimate) -> WrenchEstimate:
        wrench = np.asarray(self._true(e.t_s), float)
        if e.zeroing:
            self._zero = wrench.copy()
            return dataclasses.replace(e, calibrated=True)
        values = wrench - self._zero + self._rng.normal(0.0, 1.0, 6) * self._noise_std
        return dataclasses.replace(
            e,
            calibrated=True,
            **{name: float(v) for name, v in zip(TRUE_AXES, values, strict=True)},
        )


def oracle_noise_std(calibration: Calibration | None) -> np.ndarray:
    """Each true axis's noise (``TRUE_AXES`` order) from the task's scene calibration;
    ConfigError (one line) without one."""
    if calibration is None:
        raise ConfigError(
            "controller 'oracle': the task names no calibration (key 'calibration'); the "
            "oracle reports the truth in its units, with its measured noise"
        )
    try:
        return np.array([calibration.rest_std(axis) for axis in TRUE_AXES])
    except ValueError as exc:
        raise ConfigError(f"controller 'oracle': {exc}") from None


def _true_wrench_source(estimator: TactileEstimator, world: Any, seed: int) -> WrenchSource:
    """The estimator with ``TrueWrench`` reading the simulated ``world``'s true gel wrench at
    each frame's time, its noise seeded by ``seed``."""
    noise_std = oracle_noise_std(estimator.calibration)

    def true_wrench_at(t_s: float) -> np.ndarray:
        world.sync()
        return world.world.physics.gel_wrench_at(t_s)

    rng = np.random.default_rng([seed, 0x0AC1E])
    return TransformedSource(estimator, TrueWrench(true_wrench_at, noise_std, rng))


ORACLE = Controller(CONTROLLERS["dipole"].machine, _true_wrench_source, sim_only=True)

TRIAL_CONTROLLERS: Mapping[str, Controller] = {**CONTROLLERS, "oracle": ORACLE}
"""The controllers the trial tools compare: the product's and the oracle."""
