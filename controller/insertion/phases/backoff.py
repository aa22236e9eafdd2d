"""BACKOFF: lift the tip straight up by the back-off distance, then ALIGN again (after a
jam) or APPROACH and SEARCH again (after a press that never engaged, a catch that was not
the opening or a timeout; then also until the tip's lowest edge is the back-off distance
above the surface found) (config.BackoffSettings).
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import TYPE_CHECKING

import numpy as np

from controller.insertion.commands import hold, lift_command
from controller.insertion.interface import Command, FailureReason, Observation, Phase
from controller.insertion.machine_config import MachineConfig
from core.spatial import rotation_from_rpy

if TYPE_CHECKING:
    from controller.insertion.machine import InsertionMachine

# the guards into BACKOFF after which the machine searches again (the others: ALIGN again)
SEARCH_AGAIN = ("not_engaged", "no_wall", "not_entered", "align_timeout", "search_timeout")


class BackoffStage(Enum):
    """BACKOFF's one sub-stage."""

    LIFT = "lift"  # the TCP straight up at ``backoff.speed_m_s``


@dataclass
class BackoffState:
    """BACKOFF so far: ``z0_m`` the TCP's height on entry (m, B z)."""

    z0_m: float
    stage: BackoffStage = BackoffStage.LIFT


def enter(obs: Observation, config: MachineConfig) -> BackoffState:
    """BACKOFF entered at ``obs``."""
    return BackoffState(float(obs.arm.tcp.xyz_m[2]))


def begin(machine: InsertionMachine, obs: Observation, guard: str) -> Command:
    """Go to BACKOFF under ``guard`` (a retry); FAILED when the retries are used up."""
    memory = machine.memory
    if memory.retries >= machine.config.backoff.max_retries:
        return machine.fail(obs, FailureReason.TOO_MANY_RETRIES)
    memory.retries += 1
    memory.search_again = guard in SEARCH_AGAIN
    machine.go(obs, Phase.BACKOFF, guard)
    return hold()


def step(machine: InsertionMachine, obs: Observation, new: bool) -> Command:
    """BACKOFF's command for ``obs`` (see the module doc)."""
    state, settings = machine.state(BackoffState), machine.config.backoff
    search_again = machine.memory.search_again
    lifted = obs.arm.tcp.xyz_m[2] >= state.z0_m + settings.distance_m
    if lifted and search_again:
        # SEARCH again from clear of the board: the tip's lowest edge above the surface
        rotation = rotation_from_rpy(obs.arm.tcp.rpy_rad)
        lifted = -machine.touch.depth(obs.arm.tcp, rotation) >= settings.distance_m
    if lifted:
        if search_again:
            machine.go(obs, Phase.APPROACH, "search_again")
        else:
            machine.go(obs, Phase.ALIGN, "backed_off")
        return hold()
    machine.fire("lift")
    return lift_command(machine.config, np.array([0.0, 0.0, settings.speed_m_s]))
