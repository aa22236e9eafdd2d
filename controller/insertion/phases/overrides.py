"""The phases outside autonomy: TELEOP (the operator drives), ESTOP (latched until
acknowledged) and the terminal DONE and FAILED (hold still); and where autonomy resumes
after TELEOP or ESTOP.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import TYPE_CHECKING

from controller.insertion.commands import hold, operator_command
from controller.insertion.interface import Command, Observation, Phase
from controller.insertion.machine_config import MachineConfig
from controller.insertion.motion import tip_position

if TYPE_CHECKING:
    from controller.insertion.machine import InsertionMachine


class TeleopStage(Enum):
    """TELEOP's one sub-stage."""

    OPERATOR = "operator"  # the pad's twist and gripper buttons, until the hand-back


class EstopStage(Enum):
    """ESTOP's one sub-stage."""

    HOLD = "hold"  # still, until the button is released and acknowledged


class TerminalStage(Enum):
    """DONE's and FAILED's one sub-stage."""

    HOLD = "hold"  # still, for good


@dataclass
class OverrideState:
    """TELEOP, ESTOP or a terminal phase: nothing to remember but the sub-stage."""

    stage: TeleopStage | EstopStage | TerminalStage


def enter_teleop(obs: Observation, config: MachineConfig) -> OverrideState:
    return OverrideState(TeleopStage.OPERATOR)


def enter_estop(obs: Observation, config: MachineConfig) -> OverrideState:
    return OverrideState(EstopStage.HOLD)


def enter_terminal(obs: Observation, config: MachineConfig) -> OverrideState:
    return OverrideState(TerminalStage.HOLD)


def estop(machine: InsertionMachine, obs: Observation) -> Command:
    """ESTOP: hold; released and acknowledged: TELEOP if the operator is in control, else
    where autonomy resumes (``resume_phase``)."""
    teleop = obs.teleop
    if not teleop.estop and teleop.estop_ack:
        target = Phase.TELEOP if teleop.in_control else resume_phase(machine, obs)
        resume(machine, obs, target, "estop_acknowledged")
    else:
        machine.fire("hold")
    return hold()


def teleop(machine: InsertionMachine, obs: Observation) -> Command:
    """TELEOP: the operator's command; the hand-back: where autonomy resumes."""
    if obs.teleop.hand_back:
        resume(machine, obs, resume_phase(machine, obs), "hand_back")
        return hold()
    machine.fire("operator")
    limits = machine.config.limits
    return operator_command(
        obs.teleop, machine.config.gripper, limits.max_command_speed_m_s,
        limits.max_command_angular_speed_rad_s,
    )  # fmt: skip


def resume_phase(machine: InsertionMachine, obs: Observation) -> Phase:
    """Where autonomy resumes after TELEOP or ESTOP, from the contact state: after the
    plug was released, RETRACT; no grasp or no tactile baseline, GRASP; grasped without
    contact, APPROACH; in contact with the tip in the opening, ALIGN; otherwise SEARCH."""
    config, signals = machine.config, machine.signals
    if machine.memory.released:
        return Phase.RETRACT
    if not obs.gripper.holding or not signals.ready:
        return Phase.GRASP
    if signals.magnitude < config.approach.contact_sigma:
        return Phase.APPROACH
    tip_z = tip_position(obs.arm.tcp, machine.plug.length_m)[2]
    if tip_z < machine.hole.z_m - config.search.in_hole_depth_m:
        return Phase.ALIGN
    return Phase.SEARCH


def resume(machine: InsertionMachine, obs: Observation, target: Phase, guard: str) -> None:
    """Go to ``target``; into GRASP with the plug held, keeping the grasp: settle and
    re-zero, without capturing the open gel again (a gel pressed on the plug is no open
    reference, and opening the fingers could drop the plug from where the operator left
    it)."""
    if target is Phase.GRASP and obs.gripper.holding:
        machine.memory.keep_grasp = True
    machine.go(obs, target, guard)
