"""RELEASE: open the gripper; wait until it has stopped (config.ReleaseSettings)."""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import TYPE_CHECKING

from controller.insertion.commands import hold, open_target
from controller.insertion.interface import Command, Observation, Phase
from controller.insertion.machine_config import MachineConfig
from controller.insertion.phases.stage import Staged
from core.devices import Twist

if TYPE_CHECKING:
    from controller.insertion.machine import InsertionMachine


class ReleaseStage(Enum):
    """RELEASE's sub-stages, in order."""

    OPEN = "open"  # the open command to ``gripper.open_width_m``
    OPENING = "opening"  # at least ``release.settle_s``, until the fingers stop


@dataclass
class ReleaseState(Staged[ReleaseStage]):
    """RELEASE so far (``since_t_s``: when the open command was sent)."""


def enter(obs: Observation, config: MachineConfig) -> ReleaseState:
    """RELEASE entered at ``obs``."""
    return ReleaseState(ReleaseStage.OPEN, obs.t_s)


def step(machine: InsertionMachine, obs: Observation, new: bool) -> Command:
    """RELEASE's command for ``obs`` (see the module doc)."""
    state, config = machine.state(ReleaseState), machine.config
    machine.fire("open")
    if state.stage is ReleaseStage.OPEN:
        state.next(ReleaseStage.OPENING, obs.t_s)
        return Command(twist=Twist(), gripper=open_target(config, config.gripper.open_width_m))
    if obs.t_s - state.since_t_s >= config.release.settle_s and not obs.gripper.moving:
        machine.go(obs, Phase.RETRACT, "released")
    return hold()
