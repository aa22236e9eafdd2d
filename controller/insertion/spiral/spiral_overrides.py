"""The press-spiral machine's phases outside autonomy: TELEOP (the operator drives; the
pad's twist bounded by the machine's move and turn speeds, its gripper buttons) and ESTOP
(still, latched until the button is released and acknowledged), and where autonomy resumes
after them: RETRACT once the plug was released; with the plug held, GRASP's close (it
settles, re-zeroes the tactile reference in place and approaches again, keeping the
pattern's progress); without it, a fresh GRASP."""

from __future__ import annotations

from typing import TYPE_CHECKING

from controller.insertion.commands import operator_command
from controller.insertion.interface import Command, Observation, Phase
from controller.insertion.phases.overrides import EstopStage, OverrideState, TeleopStage
from controller.insertion.spiral.spiral_grasp import GraspStage, GraspState

if TYPE_CHECKING:
    from controller.insertion.spiral.spiral_machine import SpiralMachine


def enter_teleop(obs: Observation) -> OverrideState:
    return OverrideState(TeleopStage.OPERATOR)


def enter_estop(obs: Observation) -> OverrideState:
    return OverrideState(EstopStage.HOLD)


def estop(m: SpiralMachine, obs: Observation) -> Command:
    """ESTOP: still; released and acknowledged: TELEOP if the operator is in control, else
    where autonomy resumes."""
    teleop = obs.teleop
    if not teleop.estop and teleop.estop_ack:
        if teleop.in_control:
            m.go(obs, Phase.TELEOP, "estop_acknowledged")
        else:
            resume(m, obs, "estop_acknowledged")
    else:
        m.fire("hold")
    return m.hold()


def teleop(m: SpiralMachine, obs: Observation) -> Command:
    """TELEOP: the operator's command; the hand-back: where autonomy resumes."""
    if obs.teleop.hand_back:
        resume(m, obs, "hand_back")
        return m.hold()
    m.fire("operator")
    cfg = m.config
    return operator_command(obs.teleop, cfg.gripper, cfg.move_speed_m_s, cfg.rotate_speed_rad_s)


def resume(m: SpiralMachine, obs: Observation, guard: str) -> None:
    """Back to autonomy under ``guard``: RETRACT after the release, else GRASP, at its
    close's settle with the plug held (no open gel is taken with the plug in the fingers)."""
    if m.released:
        m.go(obs, Phase.RETRACT, guard)
        return
    m.go(obs, Phase.GRASP, guard)
    if obs.gripper.holding:
        m.state(GraspState).next(GraspStage.CLOSE, obs.t_s)
