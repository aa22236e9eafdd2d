"""FEEL, at the run's first touch: find the plug in the hand by touch (config.FeelSettings;
``grasp_estimate``). APPROACH has brought the tip down on the board beside the opening;
FEEL presses it there, rocks the TCP about the horizontal axis across the opening's width
until the in-plane torque (about T y) changes sign, where the tip's face lies flat, rocks
back until it changes sign again, and takes the mean of the two angles (the signals' lag
shifts them equally in opposite directions). From it, the plug's tilt in the hand and
where its tip really is (``InsertionMachine.grasp``, published in its
``in_hand_estimates``: the width plane, always kept). Then the tip is lifted and APPROACH
brings it over the opening.

Each new estimate's angle is the TCP's at the frame's capture time (the estimate's
``t_s``), interpolated in the angles of the ticks since FEEL began; the sign change's angle
is interpolated linearly between the two estimates either side of it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import Enum
from typing import TYPE_CHECKING

import numpy as np
from scipy.spatial.transform import Rotation

from controller.insertion.commands import tip_command
from controller.insertion.grasp_estimate import GraspEstimate
from controller.insertion.interface import Command, InHandEstimate, Observation, Phase
from controller.insertion.machine_config import MachineConfig
from controller.insertion.motion import tip_position
from controller.insertion.phases.stage import Staged
from core.spatial import rotation_from_rpy

if TYPE_CHECKING:
    from controller.insertion.machine import InsertionMachine


_HISTORY_TICKS = 100  # the ticks' rock angles kept: 1 s at 100 Hz, past any frame's latency


class FeelStage(Enum):
    """FEEL's sub-stages, in order."""

    PRESS = "press"  # the tip pressed on the board until the preload settles
    ROCK = "rock"  # turn toward the flat face until the in-plane torque changes sign
    ROCK_BACK = "rock_back"  # turn back until it changes sign again
    LIFT = "lift"  # the tip up to the approach height, turned back to the search rotation


@dataclass(kw_only=True)
class FeelState(Staged[FeelStage]):
    """FEEL so far: ``tip_z0_m`` the tip's height at contact (m, B z); ``reference`` the
    TCP rotation (T2B) at entry, from which the rock angle is measured; ``axis`` the rock
    axis (unit, B); ``direction`` the sign of the present turn about it; ``sign`` the
    in-plane torque's sign before the present turn's change; ``angles`` (t_s, rad) the
    TCP's rock angle at each recent tick; ``last`` the previous estimate's (angle, torque);
    ``flips`` the angles where the sign changed; ``reversed``: the first turn found no
    change within ``rock_max_rad`` and was reversed."""

    tip_z0_m: float
    reference: Rotation
    axis: np.ndarray
    direction: float = 0.0
    sign: float = 0.0
    angles: list[tuple[float, float]] = field(default_factory=list)
    last: tuple[float, float] | None = None
    flips: list[float] = field(default_factory=list)
    reversed: bool = False


def enter(obs: Observation, config: MachineConfig) -> FeelState:
    """FEEL entered at ``obs`` (the axis is set by the machine's opening on the first step)."""
    tip_z = float(obs.arm.tcp.xyz_m[2])  # replaced on the first step, with the plug's length
    return FeelState(
        stage=FeelStage.PRESS,
        since_t_s=obs.t_s,
        tip_z0_m=tip_z,
        reference=rotation_from_rpy(obs.arm.tcp.rpy_rad),
        axis=np.zeros(3),
    )


def step(machine: InsertionMachine, obs: Observation, new: bool) -> Command:
    """FEEL's command for ``obs`` (see the module doc)."""
    state, settings = machine.state(FeelState), machine.config.feel
    rotation = rotation_from_rpy(obs.arm.tcp.rpy_rad)
    if not state.axis.any():
        yaw = machine.hole.yaw_rad
        state.axis = np.array([-math.sin(yaw), math.cos(yaw), 0.0])
        state.tip_z0_m = float(tip_position(obs.arm.tcp, machine.plug.length_m)[2])
    angle = rock_angle(rotation, state.reference, state.axis)
    state.angles = [*state.angles[-(_HISTORY_TICKS - 1) :], (obs.t_s, angle)]
    if state.stage is FeelStage.LIFT:
        return _lift(machine, state, obs, rotation)
    torque = float(machine.signals.torque_t[1])
    if new and obs.wrench is not None:
        captured = _angle_at(state.angles, obs.wrench.t_s)
        _judge(machine, state, obs, captured, torque)
        if state.stage is FeelStage.LIFT:
            return _lift(machine, state, obs, rotation)
    if state.stage is FeelStage.PRESS:
        machine.fire("press")
        return _rock(machine, state, obs, 0.0)
    rule = state.stage.value
    if abs(angle) > settings.rock_max_rad and state.direction * angle > 0:
        if state.stage is not FeelStage.ROCK or state.reversed:
            state.next(FeelStage.LIFT, obs.t_s)
            command = _lift(machine, state, obs, rotation)
            machine.fire("no_flat_face")
            return command
        rule, state.direction, state.reversed = "reverse", -state.direction, True
    machine.fire(rule)
    return _rock(machine, state, obs, state.direction * settings.rock_speed_rad_s)


def rock_angle(rotation: Rotation, reference: Rotation, axis: np.ndarray) -> float:
    """The turn (rad) about ``axis`` (unit, B) from ``reference`` to ``rotation`` (T2B)."""
    return float(np.dot((rotation * reference.inv()).as_rotvec(), axis))


def _angle_at(angles: list[tuple[float, float]], t_s: float) -> float:
    """The rock angle at time ``t_s``, interpolated in the ticks' (t_s, angle) (clamped to
    the first and the last)."""
    times = np.array([t for t, _ in angles])
    values = np.array([a for _, a in angles])
    return float(np.interp(t_s, times, values))


def _judge(
    machine: InsertionMachine, state: FeelState, obs: Observation, angle: float, torque: float
) -> None:
    """Take a new estimate: the preload settled (PRESS), or the torque's sign changed."""
    settings = machine.config.feel
    last, state.last = state.last, (angle, torque)
    if state.stage is FeelStage.PRESS:
        if obs.t_s - state.since_t_s >= settings.settle_s:
            # a face already about flat gives a sign of noise: the turn then runs out to
            # rock_max_rad and is reversed (``step``)
            state.sign = math.copysign(1.0, torque)
            state.direction = state.sign
            state.next(FeelStage.ROCK, obs.t_s)
        return
    if last is None or abs(torque) < settings.flip_sigma or torque * state.sign > 0:
        return
    # the sign changed: where the torque crossed zero, between the last estimate and this
    (a0, t0), (a1, t1) = last, (angle, torque)
    state.flips.append(a0 + (a1 - a0) * t0 / (t0 - t1) if t0 != t1 else a1)
    state.sign = -state.sign
    if state.stage is FeelStage.ROCK:
        state.direction = -state.direction
        state.next(FeelStage.ROCK_BACK, obs.t_s)
        return
    flat = Rotation.from_rotvec(state.axis * float(np.mean(state.flips))) * state.reference
    machine.grasp = GraspEstimate.from_flat_rotation(flat, machine.plug.length_m)
    machine.publish_in_hand(InHandEstimate(
        obs.t_s, "width", machine.grasp.tilt_rad, float(machine.grasp.tip_t[0]), "rock", True
    ))  # fmt: skip
    state.next(FeelStage.LIFT, obs.t_s)


def _rock(machine: InsertionMachine, state: FeelState, obs: Observation, rate: float) -> Command:
    """The tip held ``feel.press_depth_m`` below its height at contact, turning about the
    rock axis at ``rate`` (rad/s)."""
    gain = machine.config.approach.pose_gain_1_s
    tip_z = tip_position(obs.arm.tcp, machine.plug.length_m)[2]
    v_tip = np.array(
        [0.0, 0.0, gain * (state.tip_z0_m - machine.config.feel.press_depth_m - tip_z)]
    )
    return tip_command(machine.config, machine.plug, obs, v_tip, rate * state.axis)


def _lift(
    machine: InsertionMachine, state: FeelState, obs: Observation, rotation: Rotation
) -> Command:
    """The tip up to the approach height above where it touched, turned back to the search
    rotation; there, APPROACH again (over the opening)."""
    settings = machine.config.approach
    tip_z = tip_position(obs.arm.tcp, machine.plug.length_m)[2]
    rise = state.tip_z0_m + settings.height_m - tip_z
    w = machine.hold_rotation(rotation)
    if rise <= settings.pose_tol_m and np.linalg.norm(w) <= settings.angle_tol_rad * (
        settings.pose_gain_1_s
    ):
        machine.go(obs, Phase.APPROACH, "grasp_felt")
        return tip_command(machine.config, machine.plug, obs, np.zeros(3), np.zeros(3))
    machine.fire("lift")
    v_tip = np.array([0.0, 0.0, settings.pose_gain_1_s * max(rise, 0.0)])
    return tip_command(machine.config, machine.plug, obs, v_tip, w)
