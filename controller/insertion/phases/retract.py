"""RETRACT: lift the TCP straight up by the retract distance (config.ReleaseSettings)."""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import TYPE_CHECKING

import numpy as np

from controller.insertion.commands import hold, lift_command
from controller.insertion.interface import Command, Observation, Phase
from controller.insertion.machine_config import MachineConfig

if TYPE_CHECKING:
    from controller.insertion.machine import InsertionMachine


class RetractStage(Enum):
    """RETRACT's one sub-stage."""

    LIFT = "lift"  # the TCP straight up at ``release.retract_speed_m_s``


@dataclass
class RetractState:
    """RETRACT so far: ``z0_m`` the TCP's height on entry (m, B z)."""

    z0_m: float
    stage: RetractStage = RetractStage.LIFT


def enter(obs: Observation, config: MachineConfig) -> RetractState:
    """RETRACT entered at ``obs``."""
    return RetractState(float(obs.arm.tcp.xyz_m[2]))


def step(machine: InsertionMachine, obs: Observation, new: bool) -> Command:
    """RETRACT's command for ``obs`` (see the module doc)."""
    state, settings = machine.state(RetractState), machine.config.release
    if obs.arm.tcp.xyz_m[2] >= state.z0_m + settings.retract_distance_m:
        machine.go(obs, Phase.DONE, "retracted")
        return hold()
    machine.fire("lift")
    return lift_command(machine.config, np.array([0.0, 0.0, settings.retract_speed_m_s]))
