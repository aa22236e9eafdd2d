"""GRASP: lift (after a slip), open a little (a re-grasp), capture the open gel while the
fingers travel fast to just above the plug's thickness, close, settle, re-zero and measure
the tactile baseline; resumed with the plug held (after TELEOP or ESTOP): settle, re-zero,
baseline (config.GripperSettings, SlipSettings).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum
from typing import TYPE_CHECKING

import numpy as np

from controller.insertion.commands import (
    capture_open,
    close_target,
    hold,
    lift_command,
    open_target,
)
from controller.insertion.interface import Command, Observation, Phase
from controller.insertion.machine_config import MachineConfig
from controller.insertion.phases.stage import Staged
from core.devices import Twist

if TYPE_CHECKING:
    from controller.insertion.machine import InsertionMachine


class GraspStage(Enum):
    """GRASP's sub-stages, in order; a re-grasp begins with LIFT, a resume with SETTLE."""

    START = "start"  # entered: the first tick picks LIFT, SETTLE or CAPTURE
    LIFT = "lift"  # the TCP up by ``slip.lift_m``
    OPEN = "open"  # the fingers open by ``gripper.regrasp_gap_m``, until they stop
    CAPTURE = "capture"  # the estimator takes the open gel; the fingers travel fast
    CLOSE = "close"  # the close command
    SETTLE = "settle"  # holding, not moving, for ``gripper.settle_s``
    ZERO = "zero"  # the estimator re-zeroes, then the baseline is measured


@dataclass(kw_only=True)
class GraspState(Staged[GraspStage]):
    """GRASP so far: ``z0_m`` the TCP's height on entry (m, B z); ``frame_t_s`` the time
    of the last tactile estimate counted while capturing (s)."""

    z0_m: float
    frame_t_s: float = math.nan


def enter(obs: Observation, config: MachineConfig) -> GraspState:
    """GRASP entered at ``obs``."""
    return GraspState(stage=GraspStage.START, since_t_s=obs.t_s, z0_m=float(obs.arm.tcp.xyz_m[2]))


def _first(machine: InsertionMachine) -> GraspStage:
    """The first sub-stage: LIFT after a slip, SETTLE on a resume with the plug held,
    CAPTURE otherwise."""
    if machine.memory.regrasp:
        return GraspStage.LIFT
    return GraspStage.SETTLE if machine.memory.keep_grasp else GraspStage.CAPTURE


def step(machine: InsertionMachine, obs: Observation, new: bool) -> Command:
    """GRASP's command for ``obs`` (see the module doc)."""
    state, config = machine.state(GraspState), machine.config
    settings = config.gripper
    if state.stage is GraspStage.START:
        state.stage, machine.memory.keep_grasp = _first(machine), False
        state.since_t_s = obs.t_s
        machine.fire(state.stage.value)
        if state.stage is GraspStage.CAPTURE:
            return capture_open(config, machine.plug, obs)
    else:
        machine.fire(state.stage.value)
    if state.stage is GraspStage.LIFT:
        if obs.arm.tcp.xyz_m[2] >= state.z0_m + config.slip.lift_m:
            state.next(GraspStage.OPEN, obs.t_s)
            return Command(
                twist=Twist(),
                gripper=open_target(config, obs.gripper.width_m + settings.regrasp_gap_m),
            )
        return lift_command(config, np.array([0.0, 0.0, config.approach.move_speed_m_s]))
    if state.stage is GraspStage.OPEN:
        if obs.t_s - state.since_t_s >= settings.settle_s and not obs.gripper.moving:
            machine.memory.regrasp = False
            state.next(GraspStage.CAPTURE, obs.t_s)
            return capture_open(config, machine.plug, obs)
        return hold()
    if state.stage is GraspStage.CAPTURE:
        # the open gel: the estimator takes the next zeroing_frames frames; wait for one
        # more, and for the fingers' fast travel to end
        if obs.wrench is not None and obs.wrench.t_s != state.frame_t_s:
            state.frame_t_s = obs.wrench.t_s
            state.count += 1
        if state.count > config.signals.zeroing_frames and not obs.gripper.moving:
            state.next(GraspStage.CLOSE, obs.t_s)
        return hold()
    if state.stage is GraspStage.CLOSE:
        state.next(GraspStage.SETTLE, obs.t_s)
        return Command(twist=Twist(), gripper=close_target(config))
    if state.stage is GraspStage.SETTLE:
        if not (obs.gripper.holding and not obs.gripper.moving):
            state.since_t_s = obs.t_s
        elif obs.t_s - state.since_t_s >= settings.settle_s:
            state.next(GraspStage.ZERO, obs.t_s)
            machine.signals.reset()
            return Command(twist=Twist(), rezero_tactile=True)
        return hold()
    # ZERO: wait for the estimator's zeroing, then for the baseline
    if machine.signals.ready:
        machine.go(obs, Phase.APPROACH, "grasped_and_zeroed")
    return hold()
