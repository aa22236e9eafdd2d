"""INSERT of the press-spiral machine: the caught x, y held, a push down at
``push_speed_m_s`` until the force reaches ``stop_force_n`` or the TCP has gone no more than
``stall_m`` lower for ``stall_s`` (the arm's workspace floor). ``entry_m`` or more below the
press's height the plug is in (RELEASE, ``bottomed``: on the receptacle's floor or the plug's
shoulder, however long the plug sticks out of the grasp); less, it jammed on the rim: back
up to the press at ``lift_speed_m_s``, and SEARCH's sweep goes on ``jam_skip_m`` further
along (``jammed``)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import Enum
from typing import TYPE_CHECKING

import numpy as np

from controller.insertion.interface import Command, Observation, Phase
from controller.insertion.phases.stage import Staged
from controller.insertion.spiral.spiral_search import SearchStage, SearchState

if TYPE_CHECKING:
    from controller.insertion.spiral.spiral_machine import SpiralMachine


class InsertStage(Enum):
    """INSERT's sub-stages."""

    PUSH = "push"  # down at the push speed, x, y held at the catch
    LIFT = "lift"  # jammed on the rim: back up to the press


@dataclass
class InsertState(Staged[InsertStage]):
    """INSERT's sub-stage; ``hold_xy``: the TCP's x, y at the catch (B, m), and ``tip_xy``
    the tip's at the first push (B, m; held instead when the torque servo turns the TCP
    about the tip); the push's lowest
    TCP height so far (``stall_z_m``, m; none before the first push) and when it was reached
    (``stall_t_s``, s)."""

    hold_xy: np.ndarray = field(default_factory=lambda: np.zeros(2))
    tip_xy: np.ndarray | None = None
    stall_z_m: float = math.inf
    stall_t_s: float = 0.0


def enter(obs: Observation) -> InsertState:
    """At the catch: x, y held where the TCP is; the stall's clock starts at the first push."""
    return InsertState(InsertStage.PUSH, obs.t_s, hold_xy=np.asarray(obs.arm.tcp.xyz_m[:2]))


def step(m: SpiralMachine, obs: Observation) -> Command:
    """See the module doc."""
    cfg, state = m.config, m.state(InsertState)
    force = m.tared_force(obs)
    if state.stage is InsertStage.LIFT:
        m.fire("lift")
        if force <= cfg.press_force_n:
            m.go(obs, Phase.SEARCH, "jammed")
            m.state(SearchState).stage = SearchStage.SWEEP
            m.memory.s_m += cfg.jam_skip_m
            return m.pressed(obs, force)
        return m.descend(obs, -cfg.lift_speed_m_s, hold_xy=state.hold_xy)
    z = obs.arm.tcp.xyz_m[2]
    if z < state.stall_z_m - cfg.stall_m:
        state.stall_z_m, state.stall_t_s = z, obs.t_s
    stalled = obs.t_s - state.stall_t_s >= cfg.stall_s
    if force >= cfg.stop_force_n or stalled:
        if m.tip_drop_m(obs, force) >= cfg.entry_m:
            m.go(obs, Phase.RELEASE, "bottomed", "stall" if stalled else "force")
            return m.hold()
        state.stage = InsertStage.LIFT
        m.fire("lift")
        return m.descend(obs, -cfg.lift_speed_m_s, hold_xy=state.hold_xy)
    torque_t = m.reading.torque_t()
    if m.torque_servo is not None and torque_t is not None:
        if state.tip_xy is None:
            state.tip_xy = m.tip_xy(obs)
        m.fire("servo_push")
        return m.servoed_push(obs, cfg.push_speed_m_s, state.tip_xy, torque_t)
    m.fire("push")
    return m.descend(obs, cfg.push_speed_m_s, hold_xy=state.hold_xy)
