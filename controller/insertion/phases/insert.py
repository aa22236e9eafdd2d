"""INSERT: press with a bounded load, sweeping the yaw until the plug engages; then push
straight down within the budgets; a jam backs off; the depth is success
(config.InsertSettings).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import Enum
from typing import TYPE_CHECKING

import numpy as np
from scipy.spatial.transform import Rotation

from controller.insertion.commands import hold, tip_command
from controller.insertion.interface import Command, Observation, Phase
from controller.insertion.machine_config import MachineConfig
from controller.insertion.motion import yaw_of
from controller.insertion.phases import backoff
from controller.insertion.phases.stage import Staged
from controller.insertion.servo import YawSweep, align_rate, load_rate
from core.spatial import clamp_norm, rotation_from_rpy

if TYPE_CHECKING:
    from controller.insertion.machine import InsertionMachine


class InsertStage(Enum):
    """INSERT's sub-stages: START, then PRESS (not yet in the opening) and PUSH."""

    START = "start"  # entered: the first tick picks PUSH if the plug is in, else PRESS
    PRESS = "press"  # down to the press load, then sweep the yaw until the plug engages
    PUSH = "push"  # straight down, the yaw held, until the depth or a jam


@dataclass(kw_only=True)
class InsertState(Staged[InsertStage]):
    """INSERT so far (``count``: successive estimates of a jam in PUSH; ``since_t_s``:
    PUSH's last progress). ``z0_m``: the TCP's height on entry; ``stall_z_m``: its height
    when the press load was reached, then at PUSH's last progress (m, B z); ``lowest``:
    the lowest tilt torque in PUSH (noise units); ``sweep``: PRESS's yaw sweep."""

    z0_m: float
    stall_z_m: float = math.nan
    lowest: float = math.inf
    sweep: YawSweep = field(default_factory=YawSweep)


def enter(obs: Observation, config: MachineConfig) -> InsertState:
    """INSERT entered at ``obs``."""
    return InsertState(stage=InsertStage.START, since_t_s=obs.t_s, z0_m=float(obs.arm.tcp.xyz_m[2]))


def step(machine: InsertionMachine, obs: Observation, new: bool) -> Command:
    """INSERT's command for ``obs`` (see the module doc)."""
    state, settings = machine.state(InsertState), machine.config.insert
    signals = machine.signals
    rotation = rotation_from_rpy(obs.arm.tcp.rpy_rad)
    if state.stage is InsertStage.START:
        entered = machine.touch.entered(obs.arm.tcp, rotation, machine.config.align.enter_m)
        state.next(InsertStage.PUSH if entered else InsertStage.PRESS, obs.t_s)
    target_load = settings.press_load_ratio * machine.memory.preload_sigma
    unloaded = signals.axial_force_sigma < target_load
    if machine.touch.depth(obs.arm.tcp, rotation) >= settings.depth_m and unloaded:
        machine.go(obs, Phase.RELEASE, "depth_reached")
        return hold()
    if state.stage is InsertStage.PRESS:
        return _press(machine, state, obs, target_load)
    if new:
        torque = signals.torque_t
        tilt = float(math.hypot(torque[0], torque[1]))
        state.lowest = min(state.lowest, tilt)
        jammed = (
            tilt - state.lowest >= settings.jam_rise_sigma
            or signals.axial_force > settings.force_budget
        )
        state.count = state.count + 1 if jammed else 0
    z_tcp = float(obs.arm.tcp.xyz_m[2])
    if math.isnan(state.stall_z_m) or z_tcp < state.stall_z_m - settings.progress_m:
        state.stall_z_m, state.since_t_s = z_tcp, obs.t_s
    stalled = obs.t_s - state.since_t_s >= settings.stall_s
    if state.count >= settings.jam_frames or stalled:
        machine.touch.note_jam(obs.arm.tcp, rotation, machine.config.align.enter_m)
        return backoff.begin(machine, obs, "jam")
    machine.fire("push")
    w = _compliance(machine, rotation)
    w[2] = 0.0  # the yaw found while pressing is held
    return _down(machine, obs, target_load, w)


def _press(
    machine: InsertionMachine, state: InsertState, obs: Observation, target_load: float
) -> Command:
    """PRESS: descend toward the press load (``target_load``, noise units); at the stall
    height sweep the yaw; engaged: PUSH; the sweeps done: back off and search again."""
    settings, signals = machine.config.insert, machine.signals
    z_tcp = float(obs.arm.tcp.xyz_m[2])
    rotation = rotation_from_rpy(obs.arm.tcp.rpy_rad)
    yaw = yaw_of(rotation) - machine.hole.yaw_rad
    if math.isnan(state.stall_z_m) and not (
        signals.axial_force_sigma < settings.stall_load_ratio * target_load
    ):
        state.stall_z_m = z_tcp
        state.sweep.start_yaw_rad = yaw
    reference = state.z0_m if math.isnan(state.stall_z_m) else state.stall_z_m
    gave_way = not math.isnan(state.stall_z_m) and (
        signals.axial_force_sigma < settings.give_way_ratio * target_load
    )
    if z_tcp <= reference - settings.engage_m or gave_way:
        machine.fire("engaged")
        state.next(InsertStage.PUSH, obs.t_s)
        return hold()
    w = np.zeros(3)
    if not math.isnan(state.stall_z_m) and settings.yaw_sweep_rad > 0.0:
        if state.sweep.advance(yaw, settings.yaw_sweep_rad, settings.sweeps):
            return backoff.begin(machine, obs, "not_engaged")
        w[2] = state.sweep.sign * settings.yaw_rate_rad_s
    machine.fire("press" if w[2] == 0.0 else "yaw_sweep")
    w[:2] = _compliance(machine, rotation)[:2]
    return _down(machine, obs, target_load, w)


def _compliance(machine: InsertionMachine, rotation: Rotation) -> np.ndarray:
    """ALIGN's torque servo at ``insert.compliance_scale`` of its gains (rad/s, B)."""
    align = machine.config.align
    return clamp_norm(
        align_rate(machine.signals, align, rotation, machine.config.insert.compliance_scale),
        align.max_turn_speed_rad_s,
    )


def _down(
    machine: InsertionMachine, obs: Observation, target_load: float, w: np.ndarray
) -> Command:
    """The tip down at ``insert.speed_m_s`` times the load's shortfall below
    ``target_load`` (noise units, within +-1), turning at ``w`` (rad/s, B)."""
    speed = load_rate(machine.signals, target_load, machine.config.insert.speed_m_s)
    return tip_command(machine.config, machine.plug, obs, np.array([0.0, 0.0, -speed]), w)
