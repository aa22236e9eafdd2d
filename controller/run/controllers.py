"""The controllers a run can use, by name: each is a machine and the wrench source that
feeds it. This table is the one place controller names are defined; the tools offer its
keys (evaluation adds the simulation-only ``oracle`` for its comparisons).

* ``dipole``: the insertion machine on the estimator as it is (dipole tilt, NHHD in-plane
  torque): the product;
* ``fingervision``: the same machine on the FingerVision baseline's torques
  (``fv_tau_*``, ``fingervision_torques``);
* ``blind``: a spiral of pushes without tactile feedback (``BlindMachine``); the estimator
  still runs, and its estimates are recorded, never used.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from controller.insertion import InsertionMachine, Machine
from controller.insertion.blind import BlindMachine
from controller.run.task import TaskConfig
from controller.tactile import TactileEstimator, TransformedSource, WrenchEstimate, WrenchSource


def fingervision_torques(estimate: WrenchEstimate) -> WrenchEstimate:
    """``estimate`` with its torques replaced by the FingerVision baseline's
    (``fv_tau_x``, ``fv_tau_y``, ``fv_tau_z``; raw units as the estimate's)."""
    e = estimate
    return dataclasses.replace(e, tau_x=e.fv_tau_x, tau_y=e.fv_tau_y, tau_z=e.fv_tau_z)


@dataclass(frozen=True)
class Controller:
    """A named controller: ``machine(task_config)`` builds its state machine;
    ``wrench_source(estimator, world)`` the source of the estimates it sees (``world``: the
    simulated world, None on hardware; only simulation-only controllers may read it).
    ``sim_only``: refused on the real backend."""

    machine: Callable[[TaskConfig], Machine]
    wrench_source: Callable[[TactileEstimator, Any], WrenchSource]
    sim_only: bool = False


def _insertion_machine(config: TaskConfig) -> Machine:
    return InsertionMachine(config.machine, config.plug, config.hole)


def _blind_machine(config: TaskConfig) -> Machine:
    return BlindMachine(config.blind, config.plug, config.hole)


def _the_estimator(estimator: TactileEstimator, world: Any) -> TactileEstimator:
    return estimator


def _baseline(estimator: TactileEstimator, world: Any) -> WrenchSource:
    return TransformedSource(estimator, fingervision_torques)


CONTROLLERS: Mapping[str, Controller] = {
    "dipole": Controller(_insertion_machine, _the_estimator),
    "fingervision": Controller(_insertion_machine, _baseline),
    "blind": Controller(_blind_machine, _the_estimator),
}
