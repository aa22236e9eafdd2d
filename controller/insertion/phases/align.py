"""ALIGN, after SEARCH caught the tilted tip's lowest edge (the heel) in the opening: seek
the wall with the heel, turn upright about it, slide along the width or sweep the yaw until
the plug enters, then null the torques (config.AlignSettings; docs/ARCHITECTURE.md,
"ALIGN").
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import Enum
from typing import TYPE_CHECKING

import numpy as np
from scipy.spatial.transform import Rotation

from controller.insertion.commands import hold, tip_command, twist_command
from controller.insertion.interface import Command, Observation, Phase
from controller.insertion.machine_config import MachineConfig
from controller.insertion.motion import lowest_edge, pivot_twist, tip_position, yaw_of
from controller.insertion.phases import backoff
from controller.insertion.phases.stage import Staged
from controller.insertion.search_path import lateral_resistance
from controller.insertion.servo import (
    YawSweep,
    align_rate,
    heel_yaw_rate,
    load_rate,
    torques_within_tolerance,
)
from core.spatial import (
    clamp_norm,
    rotation_from_rpy,
    tilt_of_tool_axis,
)

if TYPE_CHECKING:
    from controller.insertion.machine import InsertionMachine


class AlignStage(Enum):
    """ALIGN's sub-stages: START, then SEEK and TURN (or straight to what follows TURN when
    already upright), then SERVO if the plug entered, else WIDTH and YAW first."""

    START = "start"  # entered: the first tick picks SEEK, or what follows TURN
    SEEK = "seek"  # the heel against the tilt's lean until the wall holds it
    TURN = "turn"  # upright about the heel, held against the wall
    WIDTH = "width"  # slide along T x toward the low end the in-plane torque names
    YAW = "yaw"  # sweep the yaw until the plug enters
    SERVO = "servo"  # the plug in the opening: yield to the torques until aligned


@dataclass(kw_only=True)
class AlignState(Staged[AlignStage]):
    """ALIGN so far (``count``: successive estimates satisfying the present sub-stage's
    rule). ``direction``: the horizontal unit vector in B the heel moves along (SEEK, TURN:
    against the lean; WIDTH: toward the low end); ``point``: where that began, in B (m;
    SEEK: the heel at its start, TURN: the heel where the wall held it, WIDTH: the tip);
    ``resistance0``: the lateral resistance when it began and ``rise`` its rise since
    (noise units); ``sweep``: the YAW stage's sweep."""

    direction: np.ndarray = field(default_factory=lambda: np.zeros(3))
    point: np.ndarray = field(default_factory=lambda: np.zeros(3))
    resistance0: float = math.nan
    rise: float = 0.0
    sweep: YawSweep = field(default_factory=YawSweep)


def enter(obs: Observation, config: MachineConfig) -> AlignState:
    """ALIGN entered at ``obs``."""
    return AlignState(stage=AlignStage.START, since_t_s=obs.t_s)


def step(machine: InsertionMachine, obs: Observation, new: bool) -> Command:
    """ALIGN's command for ``obs`` (see the module doc)."""
    state, settings = machine.state(AlignState), machine.config.align
    rotation = rotation_from_rpy(obs.arm.tcp.rpy_rad)
    plug_tilt = tilt_of_tool_axis(machine.plug_axis_b(rotation))[0]
    if state.stage is AlignStage.START and plug_tilt <= settings.tilt_tol_rad:
        # upright already (after a jam's back-off): no heel to seek or turn about
        _after_upright(machine, state, obs, rotation)
    if state.stage is AlignStage.START:
        state.next(AlignStage.SEEK, obs.t_s)
        lean = rotation.apply([0.0, 0.0, 1.0])
        lean[2] = 0.0
        norm = float(np.linalg.norm(lean))
        state.direction = -lean / norm if norm > 1e-9 else np.zeros(3)
        state.point = lowest_edge(obs.arm.tcp, machine.plug, rotation)
    if state.stage is AlignStage.SERVO:
        return _servo(machine, state, obs, new)
    if state.stage is AlignStage.WIDTH:
        return _width(machine, state, obs, rotation, new)
    if state.stage is AlignStage.YAW:
        return _yaw(machine, state, obs, rotation, new)
    if new and np.linalg.norm(state.direction) > 0.0:
        resistance = lateral_resistance(machine.signals, rotation, state.direction)[1]
        if math.isnan(state.resistance0):
            state.resistance0 = resistance
        state.rise = resistance - state.resistance0
        held = state.rise >= settings.wall_sigma
        state.count = state.count + 1 if held else 0
    if state.stage is AlignStage.SEEK:
        return _seek(machine, state, obs, rotation)
    return _turn(machine, state, obs, rotation)


def _press_rate(machine: InsertionMachine) -> float:
    """Downward tip speed (m/s) pressing with SEARCH's load, at most the descent speed."""
    return load_rate(
        machine.signals, machine.memory.preload_sigma, machine.config.approach.descend_speed_m_s
    )


def _press_down(machine: InsertionMachine, obs: Observation, w: np.ndarray) -> Command:
    """The tip straight down pressing with SEARCH's load, turning at ``w`` (rad/s, B)."""
    v_tip = np.array([0.0, 0.0, -_press_rate(machine)])
    return tip_command(machine.config, machine.plug, obs, v_tip, w)


def _entered(machine: InsertionMachine, obs: Observation, rotation: Rotation) -> bool:
    return machine.touch.entered(obs.arm.tcp, rotation, machine.config.align.enter_m)


def _seek(
    machine: InsertionMachine, state: AlignState, obs: Observation, rotation: Rotation
) -> Command:
    """SEEK: the heel against the lean until the wall holds it; no wall within
    ``align.seek_max_m``: not the opening."""
    settings = machine.config.align
    edge = lowest_edge(obs.arm.tcp, machine.plug, rotation)
    moved = float(np.linalg.norm((edge - state.point)[:2]))
    if state.count >= settings.frames or not np.any(state.direction):
        machine.fire("wall")
        state.next(AlignStage.TURN, obs.t_s)
        state.point = edge
        return hold()
    if moved >= settings.seek_max_m:
        return backoff.begin(machine, obs, "no_wall")
    machine.fire("seek")
    v_edge = settings.seek_speed_m_s * state.direction
    v_edge[2] = -_press_rate(machine)
    v_tcp, w = pivot_twist(
        np.asarray(obs.arm.tcp.xyz_m, dtype=float),
        edge,
        v_edge,
        heel_yaw_rate(machine.signals, settings, rotation),
    )
    return twist_command(machine.config, v_tcp, w)


def _turn(
    machine: InsertionMachine, state: AlignState, obs: Observation, rotation: Rotation
) -> Command:
    """TURN: upright about the heel, the heel held against the wall."""
    settings = machine.config.align
    angle, axis = tilt_of_tool_axis(machine.plug_axis_b(rotation))
    if angle <= settings.tilt_tol_rad:
        machine.fire("upright")
        _after_upright(machine, state, obs, rotation)
        return hold()
    machine.fire("turn")
    edge = lowest_edge(obs.arm.tcp, machine.plug, rotation)
    held = float(np.clip(1.0 - state.rise / settings.wall_sigma, -1.0, 1.0))
    v_edge = settings.seek_speed_m_s * held * state.direction
    v_edge[2] = machine.config.approach.pose_gain_1_s * (state.point[2] - edge[2])
    yaw_rate = heel_yaw_rate(machine.signals, settings, rotation)
    w = clamp_norm(
        settings.upright_gain_1_s * angle * axis + yaw_rate, settings.max_turn_speed_rad_s
    )
    v_tcp, w = pivot_twist(np.asarray(obs.arm.tcp.xyz_m, dtype=float), edge, v_edge, w)
    return twist_command(machine.config, v_tcp, w)


def _after_upright(
    machine: InsertionMachine, state: AlignState, obs: Observation, rotation: Rotation
) -> None:
    """The sub-stage after TURN: SERVO if the plug is in the opening, else WIDTH (toward
    the low end the in-plane torque names), or YAW when the in-plane torque names no side
    (below ``align.width_sigma``) or WIDTH is off; the yaw sweep starts from here."""
    settings, signals = machine.config.align, machine.signals
    if _entered(machine, obs, rotation):
        state.next(AlignStage.SERVO, obs.t_s)
    elif settings.width_speed_m_s > 0.0 and (
        abs(float(signals.normalised[2])) >= settings.width_sigma
    ):
        state.next(AlignStage.WIDTH, obs.t_s)
        toward = -math.copysign(1.0, float(signals.normalised[2]))
        along = rotation.apply([toward, 0.0, 0.0])
        along[2] = 0.0
        state.direction = along / np.linalg.norm(along)
        state.point = tip_position(obs.arm.tcp, machine.plug.length_m)
        state.resistance0 = math.nan
    else:
        state.next(AlignStage.YAW, obs.t_s)
    state.sweep.start_yaw_rad = yaw_of(rotation) - machine.hole.yaw_rad


def _width(
    machine: InsertionMachine, state: AlignState, obs: Observation, rotation: Rotation, new: bool
) -> Command:
    """WIDTH (see config.AlignSettings): slide toward the low end, pressing, until the plug
    enters; the end wall or ``width_max_m`` first: YAW."""
    settings = machine.config.align
    if _entered(machine, obs, rotation):
        machine.fire("entered")
        state.next(AlignStage.SERVO, obs.t_s)
        return hold()
    if new:
        resistance = lateral_resistance(machine.signals, rotation, state.direction)[1]
        if math.isnan(state.resistance0):
            state.resistance0 = resistance
        held = resistance - state.resistance0 >= settings.wall_sigma
        state.count = state.count + 1 if held else 0
    tip = tip_position(obs.arm.tcp, machine.plug.length_m)
    slid = float(np.linalg.norm((tip - state.point)[:2]))
    if state.count >= settings.frames or slid >= settings.width_max_m:
        machine.fire("end_wall" if state.count >= settings.frames else "width_done")
        state.next(AlignStage.YAW, obs.t_s)
        return hold()
    machine.fire("width_slide")
    v_tip = settings.width_speed_m_s * state.direction
    v_tip[2] = -_press_rate(machine)
    return tip_command(
        machine.config, machine.plug, obs, v_tip, heel_yaw_rate(machine.signals, settings, rotation)
    )


def _yaw(
    machine: InsertionMachine, state: AlignState, obs: Observation, rotation: Rotation, new: bool
) -> Command:
    """YAW (upright but not in the opening): sweep the yaw about the tip axis within
    +-``insert.yaw_sweep_rad`` of the opening's nominal yaw, pressing with SEARCH's load,
    until the plug enters (SERVO); back where the sweep began after ``insert.sweeps``
    whole sweeps: a plug at least ``align.entering_ratio`` x ``align.enter_m`` in goes on
    to SERVO, any other is not over the opening (BACKOFF, then SEARCH again)."""
    settings, insert = machine.config.align, machine.config.insert
    if _entered(machine, obs, rotation):
        machine.fire("entered")
        state.next(AlignStage.SERVO, obs.t_s)
        return hold()
    if new and settings.twist_sigma > 0.0:
        twisted = abs(float(machine.signals.torque_t[2])) >= settings.twist_sigma
        state.count = state.count + 1 if twisted else 0
        if state.count >= settings.frames:
            machine.fire("twist_held")  # the long walls hold the yaw: in the slot
            state.next(AlignStage.SERVO, obs.t_s)
            return hold()
    yaw = yaw_of(rotation) - machine.hole.yaw_rad
    if state.sweep.advance(yaw, insert.yaw_sweep_rad, insert.sweeps):
        depth_in = machine.touch.depth_in(obs.arm.tcp, rotation)
        if depth_in >= settings.entering_ratio * settings.enter_m:
            machine.fire("entering")  # on its way in as the sweep ends: the servo
            state.next(AlignStage.SERVO, obs.t_s)
            return hold()
        return backoff.begin(machine, obs, "not_entered")
    machine.fire("yaw_sweep")
    w = np.array([0.0, 0.0, state.sweep.sign * insert.yaw_rate_rad_s])
    return _press_down(machine, obs, w)


def _servo(machine: InsertionMachine, state: AlignState, obs: Observation, new: bool) -> Command:
    """SERVO (the plug in the opening): yield to the torques about the tip, pressing with
    SEARCH's load; aligned once every torque is within tolerance under at least
    ``align.aligned_load_ratio`` of that load, or once the plug is down to INSERT's depth."""
    settings, signals = machine.config.align, machine.signals
    if new:
        load = machine.memory.preload_sigma
        loaded = signals.axial_force_sigma >= settings.aligned_load_ratio * load
        aligned = loaded and torques_within_tolerance(signals, settings)
        state.count = state.count + 1 if aligned else 0
    rotation = rotation_from_rpy(obs.arm.tcp.rpy_rad)
    if machine.touch.depth(obs.arm.tcp, rotation) >= machine.config.insert.depth_m:
        state.count = settings.frames  # slid in while turning: INSERT judges the depth
    if state.count >= settings.frames:
        machine.go(obs, Phase.INSERT, "aligned")
        return hold()
    within = torques_within_tolerance(signals, settings)
    machine.fire("within_tolerance" if within else "torque_servo")
    w = clamp_norm(align_rate(signals, settings, rotation, 1.0), settings.max_turn_speed_rad_s)
    return _press_down(machine, obs, w)
