"""GRASP of the press-spiral machine: the fingers fast to just above the plug, then a slow
close, held still for ``gripper.settle_s``. With a tactile reading, the estimator takes the
open gel while the fingers travel (at least ``open_frames`` new frames) and re-zeroes after
the close, in the air on the way to the board (the tare waits for its readings)."""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum
from typing import TYPE_CHECKING

from controller.insertion.interface import Command, Observation, Phase
from controller.insertion.phases.stage import Staged
from core.devices import Twist

if TYPE_CHECKING:
    from controller.insertion.spiral.spiral_machine import SpiralMachine


class GraspStage(Enum):
    """GRASP's sub-stages."""

    START = "start"  # nothing sent yet
    PRECLOSE = "preclose"  # the fingers fast to just above the plug; the open gel taken
    CLOSE = "close"  # the slow close, then still for the settle time


@dataclass
class GraspState(Staged[GraspStage]):
    """GRASP's sub-stage, and the tactile frames seen while the open gel is taken (``frames``
    new estimates, the newest captured at ``frame_t_s``, s)."""

    frames: int = 0
    frame_t_s: float = float("nan")


def enter(obs: Observation) -> GraspState:
    return GraspState(GraspStage.START, obs.t_s)


def step(m: SpiralMachine, obs: Observation) -> Command:
    """See the module doc."""
    g, state = m.config.gripper, m.state(GraspState)
    zeroes = m.reading.zeroes_tactile
    if state.stage is GraspStage.START:
        state.stage = GraspStage.PRECLOSE
        target = g.preclose_target(m.plug.thickness_m, obs.gripper.width_m)
        if target is not None or zeroes:
            m.fire("preclose")
            return Command(twist=Twist(), gripper=target, capture_open_tactile=zeroes)
    if state.stage is GraspStage.PRECLOSE:
        if obs.wrench is not None and obs.wrench.t_s != state.frame_t_s:
            state.frame_t_s, state.frames = obs.wrench.t_s, state.frames + 1
        if obs.gripper.moving or (zeroes and state.frames <= m.config.open_frames):
            m.fire("preclose")
            return Command(twist=Twist())
        state.next(GraspStage.CLOSE, obs.t_s)
        m.fire("close")
        return Command(twist=Twist(), gripper=g.close_target())
    if not (obs.gripper.holding and not obs.gripper.moving):
        state.since_t_s = obs.t_s
    elif obs.t_s - state.since_t_s >= g.settle_s:
        if zeroes:  # the new reference is taken in the air on the way (the tare waits)
            m.fire("zero")
        m.go(obs, Phase.APPROACH, "grasped")
        return Command(twist=Twist(), rezero_tactile=zeroes)
    m.fire("close")
    return Command(twist=Twist())
