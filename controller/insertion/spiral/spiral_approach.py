"""APPROACH of the press-spiral machine: the plug upright, at the first pass's yaw, to
``hover_m`` above the nominal opening."""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import TYPE_CHECKING

from controller.insertion.interface import Command, Observation, Phase
from controller.insertion.phases.stage import Staged
from core.devices import Twist

if TYPE_CHECKING:
    from controller.insertion.spiral.spiral_machine import SpiralMachine


class ApproachStage(Enum):
    """APPROACH's one sub-stage."""

    MOVE = "move"  # servo to the hover above the pattern's start


@dataclass
class ApproachState(Staged[ApproachStage]):
    """APPROACH's sub-stage."""


def enter(obs: Observation) -> ApproachState:
    return ApproachState(ApproachStage.MOVE, obs.t_s)


def step(m: SpiralMachine, obs: Observation) -> Command:
    """See the module doc."""
    target = m.tip_target(0.0, m.config.hover_m)
    if m.reach(obs, target):
        m.go(obs, Phase.SEARCH, "above_the_opening")
        return Command(twist=Twist())
    m.fire("move")
    return m.servo(obs, target)
