"""APPROACH: servo to the tilted pose above the opening (the tip rising first if it is below
its height there, so the plug never sweeps over the board), then descend until contact
(config.ApproachSettings). The pose is over where SEARCH's pattern left off, with the tip
where FEEL found it; when FEEL is to run first, beside the opening (``feel.offset_m``), and
the contact there begins FEEL.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import TYPE_CHECKING

import numpy as np

from controller.insertion.commands import hold, tip_command, twist_command
from controller.insertion.interface import Command, Observation, Phase
from controller.insertion.machine_config import MachineConfig
from controller.insertion.motion import rotation_error, tip_position
from controller.insertion.phases.stage import Staged
from core.spatial import clamp_norm, rotation_from_rpy

if TYPE_CHECKING:
    from controller.insertion.machine import InsertionMachine


class ApproachStage(Enum):
    """APPROACH's sub-stages, in order."""

    POSE = "pose"  # the TCP to the tilted pose, the tip ``approach.height_m`` above
    DESCEND = "descend"  # the tip down at ``approach.descend_speed_m_s`` until contact


@dataclass
class ApproachState(Staged[ApproachStage]):
    """APPROACH so far (``count``: successive estimates in contact while descending)."""


def enter(obs: Observation, config: MachineConfig) -> ApproachState:
    """APPROACH entered at ``obs``."""
    return ApproachState(ApproachStage.POSE, obs.t_s)


def step(machine: InsertionMachine, obs: Observation, new: bool) -> Command:
    """APPROACH's command for ``obs`` (see the module doc)."""
    state, settings = machine.state(ApproachState), machine.config.approach
    rotation = rotation_from_rpy(obs.arm.tcp.rpy_rad)
    if state.stage is ApproachStage.POSE:
        target_tip = _target_tip(machine)
        target_rot = machine.search_rotation()
        target_tcp = (
            target_tip
            - target_rot.apply([0.0, 0.0, machine.plug.length_m])
            - machine.tip_shift_b(target_rot)
        )
        error = target_tcp - np.asarray(obs.arm.tcp.xyz_m)
        turn = rotation_error(rotation, target_rot)
        tip_z = tip_position(obs.arm.tcp, machine.plug.length_m)[2]
        if tip_z < target_tip[2] - settings.pose_tol_m:
            # the tip straight up to its height first, not turning (it may be in the
            # opening)
            error = np.array([0.0, 0.0, target_tip[2] - tip_z + settings.pose_tol_m])
            turn = np.zeros(3)
        if np.linalg.norm(error) <= settings.pose_tol_m and (
            np.linalg.norm(turn) <= settings.angle_tol_rad
        ):
            state.next(ApproachStage.DESCEND, obs.t_s)
        else:
            machine.fire("pose_servo")
            v = clamp_norm(settings.pose_gain_1_s * error, settings.move_speed_m_s)
            w = clamp_norm(settings.pose_gain_1_s * turn, settings.rotate_speed_rad_s)
            return twist_command(machine.config, v, w)
    if new:
        contact = machine.signals.magnitude >= settings.contact_sigma
        state.count = state.count + 1 if contact else 0
    if state.count >= settings.contact_frames:
        machine.touch.touch_surface(obs.arm.tcp, rotation)
        if machine.feel_first():
            machine.go(obs, Phase.FEEL, "first_contact")
        else:
            machine.go(obs, Phase.SEARCH, "surface_contact")
        return hold()
    machine.fire("descend")
    v_tip = np.array([0.0, 0.0, -settings.descend_speed_m_s])
    return tip_command(machine.config, machine.plug, obs, v_tip, machine.hold_rotation(rotation))


def _target_tip(machine: InsertionMachine) -> np.ndarray:
    """Where APPROACH brings the tip, in B (m): above the feel point before FEEL has run
    (``InsertionMachine.feel_first``), else above where SEARCH's pattern left off;
    ``approach.height_m`` above the nominal opening, or ``approach.touched_height_m`` above
    the surface FEEL touched once it has run."""
    if machine.feel_first():
        yaw = machine.hole.yaw_rad
        offset = machine.config.feel.offset_m * np.array([-np.sin(yaw), np.cos(yaw), 0.0])
    else:
        offset = machine.pattern_offset_b(machine.memory.search_s_m)
    settings, surface_z = machine.config.approach, machine.touch.surface_z_m
    if surface_z is None or not machine.memory.felt:
        return machine.hole_xyz + offset + np.array([0.0, 0.0, settings.height_m])
    above = machine.hole_xyz + offset
    above[2] = surface_z + settings.touched_height_m
    return above
