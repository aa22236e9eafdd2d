"""RELEASE and RETRACT of the press-spiral machine: the fingers open and, ``gripper.settle_s``
later and still, the TCP rises ``retract_m`` straight up."""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import TYPE_CHECKING

from controller.insertion.interface import Command, Observation, Phase
from controller.insertion.phases.stage import Staged
from core.devices import Twist

if TYPE_CHECKING:
    from controller.insertion.spiral.spiral_machine import SpiralMachine


class ReleaseStage(Enum):
    """RELEASE's sub-stages."""

    START = "start"  # the open not yet sent
    OPEN = "open"  # opening, then still for the settle time


class RetractStage(Enum):
    """RETRACT's one sub-stage."""

    LIFT = "lift"  # straight up from where the release ended


@dataclass
class ReleaseState(Staged[ReleaseStage]):
    """RELEASE's sub-stage."""


@dataclass
class RetractState(Staged[RetractStage]):
    """RETRACT's sub-stage and the TCP's height when it began (``z0_m``, B, m)."""

    z0_m: float = 0.0


def enter_release(obs: Observation) -> ReleaseState:
    return ReleaseState(ReleaseStage.START, obs.t_s)


def enter_retract(obs: Observation) -> RetractState:
    return RetractState(RetractStage.LIFT, obs.t_s, z0_m=obs.arm.tcp.xyz_m[2])


def release(m: SpiralMachine, obs: Observation) -> Command:
    """RELEASE (see the module doc)."""
    g, state = m.config.gripper, m.state(ReleaseState)
    m.fire("open")
    if state.stage is ReleaseStage.START:
        state.next(ReleaseStage.OPEN, obs.t_s)
        return Command(twist=Twist(), gripper=g.open_target(g.open_width_m))
    if obs.t_s - state.since_t_s >= g.settle_s and not obs.gripper.moving:
        m.go(obs, Phase.RETRACT, "released")
        return m.hold()
    return Command(twist=Twist())


def retract(m: SpiralMachine, obs: Observation) -> Command:
    """RETRACT (see the module doc)."""
    if obs.arm.tcp.xyz_m[2] >= m.state(RetractState).z0_m + m.config.retract_m:
        m.go(obs, Phase.DONE, "retracted")
        return m.hold()
    m.fire("lift")
    return Command(twist=Twist((0.0, 0.0, m.config.move_speed_m_s)))
