"""The controllers a run can use, by name: each is a machine and the wrench source that
feeds it. This table is the one place controller names are defined; the tools offer its
keys (evaluation adds the simulation-only ``oracle`` for its comparisons).

* ``dipole``: the product: the press-spiral machine by touch (``SpiralMachine`` with the
  task's ``touch_spiral:`` settings; controller/insertion/spiral/) on the estimator as it is
  (dipole tilt, NHHD in-plane torque): the plug's axial force read from the estimate
  (``TactileAxialForce``), its torques for INSERT's optional torque servo; it reads only the
  estimate and the arm's and the gripper's status, never the arm's F/T sensor;
* ``fingervision``: the same machine on the FingerVision baseline's torques
  (``fv_tau_*``, ``fingervision_torques``), calibrated by their own per-axis fit in the
  task's calibration and in the machine's sign convention;
* ``zero_torque`` (ablation): the same machine with tau_x, tau_y and tau_z forced to zero,
  the forces kept (``zero_torques``): what the machine does without the torques;
* ``torque_only`` (ablation): the same machine with the shear and the normal force forced
  to zero, the torques kept (``torques_only``);
* ``align``: the find-align-insert machine (``InsertionMachine``, the task's ``machine:``
  settings) on the estimator as it is: the paper's teleoperated demo's cues (the tilt
  torques), closed in a loop;
* ``blind``: the strongest search without touch (``SpiralMachine`` with the task's
  ``blind:`` settings: a force-threshold spiral with yaw steps on the arm's own status, its
  F/T sensor's force and its pose); the estimator still runs, and its estimates are
  recorded, never used.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from controller.insertion import InsertionMachine, Machine
from controller.insertion.force_reading import TactileAxialForce
from controller.insertion.imprint import FaceOffset
from controller.insertion.machine_config import s2t_matrix
from controller.insertion.spiral import SpiralMachine
from controller.insertion.spiral.torque_servo import TorqueServo
from controller.run.task import TaskConfig
from controller.tactile import TactileEstimator, TransformedSource, WrenchEstimate, WrenchSource


def fingervision_torques(estimate: WrenchEstimate) -> WrenchEstimate:
    """``estimate`` with its torques replaced by the FingerVision baseline's
    (``fv_tau_x``, ``fv_tau_y``, ``fv_tau_z``; raw units as the estimate's)."""
    e = estimate
    return dataclasses.replace(e, tau_x=e.fv_tau_x, tau_y=e.fv_tau_y, tau_z=e.fv_tau_z)


def zero_torques(estimate: WrenchEstimate) -> WrenchEstimate:
    """``estimate`` with tau_x, tau_y and tau_z zero (the forces and the flags kept)."""
    return dataclasses.replace(estimate, tau_x=0.0, tau_y=0.0, tau_z=0.0)


def torques_only(estimate: WrenchEstimate) -> WrenchEstimate:
    """``estimate`` with shear_x, shear_y and normal zero (the torques and the flags kept)."""
    return dataclasses.replace(estimate, shear_x=0.0, shear_y=0.0, normal=0.0)


@dataclass(frozen=True)
class Controller:
    """A named controller: ``machine(task_config)`` builds its state machine;
    ``wrench_source(estimator, world, seed)`` the source of the estimates it sees (``world``:
    the simulated world, None on hardware; only simulation-only controllers may read it;
    ``seed``: the run's seed, for a source's own randomness). ``sim_only``: refused on the
    real backend. ``arm_force``: the machine reads the arm's force
    (``ArmStatus.external_force_n``): the run switches the twin's F/T sensor on, and refuses
    a real arm whose file has none."""

    machine: Callable[[TaskConfig], Machine]
    wrench_source: Callable[[TactileEstimator, Any, int], WrenchSource]
    sim_only: bool = False
    arm_force: bool = False


def _insertion_machine(config: TaskConfig) -> Machine:
    """The find-align-insert machine (``align``)."""
    return InsertionMachine(config.machine, config.plug, config.hole)


def _blind_machine(config: TaskConfig) -> Machine:
    """The press spiral on the arm's F/T sensor (``blind``)."""
    return SpiralMachine(config.blind, config.plug, config.hole)


def _touch_spiral_machine(config: TaskConfig) -> Machine:
    """The press spiral by touch (the product's machine): the axial force read from the
    estimate, its torques turned into T for the torque servo when ``push_servo.on``, for
    FEEL's rock when ``rock.enabled`` and for the near misses when ``near_miss.enabled``;
    the plug's offset across the fingers from the grasp's imprint when ``imprint_gain`` > 0."""
    spiral = config.touch_spiral
    s2t = s2t_matrix(config.machine.signals.torque_axes)
    reading = TactileAxialForce(spiral.axial_weights, spiral.force_window, s2t)
    servo = TorqueServo(spiral.push_servo) if spiral.push_servo.on else None
    face = FaceOffset(spiral.imprint_gain, s2t) if spiral.imprint_gain > 0 else None
    return SpiralMachine(
        spiral, config.plug, config.hole, reading, servo, spiral.rock, spiral.near_miss, face
    )


def _the_estimator(estimator: TactileEstimator, world: Any, seed: int) -> TactileEstimator:
    return estimator


def _transformed(
    transform: Callable[[WrenchEstimate], WrenchEstimate],
) -> Callable[[TactileEstimator, Any, int], WrenchSource]:
    """The wrench source factory of the estimator with each estimate through ``transform``."""

    def source(estimator: TactileEstimator, world: Any, seed: int) -> WrenchSource:
        return TransformedSource(estimator, transform)

    return source


CONTROLLERS: Mapping[str, Controller] = {
    "dipole": Controller(_touch_spiral_machine, _the_estimator),
    "fingervision": Controller(_touch_spiral_machine, _transformed(fingervision_torques)),
    "zero_torque": Controller(_touch_spiral_machine, _transformed(zero_torques)),
    "torque_only": Controller(_touch_spiral_machine, _transformed(torques_only)),
    "align": Controller(_insertion_machine, _the_estimator),
    "blind": Controller(_blind_machine, _the_estimator, arm_force=True),
}
