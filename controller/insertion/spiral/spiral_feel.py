"""FEEL of the press-spiral machine on touch: the plug's tilt in the hand about T x (its
thickness plane) and, with ``width``, about T y (its width plane), found by rocking it on the
board at the touch of SEARCH's pass ``at_pass`` (0: the first; later, a plug that goes in at
the first pass loses no time).

Why: a plug turned in the fingers about its width axis meets a slot barely wider than it
(USB-C: 2.6 mm for 2.4 mm) at that tilt, and no spiral position lets it in; turned upright
it goes in. Pressed on the board, the tip's face stands on one of its two long edges, and
the tilt torque about T x is the press times that edge's lever; where the face lies flat the
contact jumps to the other edge and the torque jumps by about the press times the plug's
thickness. So FEEL rocks the TCP about the tip, about T x, while the admittance holds the
press: up to ``rock_max_rad`` one way (**rock**), then the other way (**rock_back**), and,
when the first leg found no step (the flat angle lies the other side of upright), the first
way again (**rock_again**), taking each new frame's torque about T x with the TCP's rock
angle at the frame's capture time. The flat angle of a leg is where the torque's step (the
mean of ``window`` frames after less the mean of ``window`` before) is largest; the
estimate is the mean of two legs' in opposite directions (the signals' lag shifts them
equally the two ways), kept when both steps reach ``min_step_nm`` and the two angles agree
within ``agree_rad``; the TCP then **turn**s by it. With ``width``, the same three legs
about T y follow (**width_rock**, ...: the face's short edges, the torque about T y, which is
the gel's in-plane torque), the plug already upright in its thickness plane, and the TCP
turns back upright about T y (**width_turn**). That estimate places the tip only: the tilt
in the width plane moves the tip along T x by up to 1.7 mm (5 degrees, 20 mm), which added to
the opening's offset put it beyond the spiral's reach; the plug is not turned upright in
that plane, where the wrist's compliance sets it in the opening (an 8 mm lever; turned by
the estimate, 7 of 35 tuning seeds that went in no longer did, docs/BENCHMARKS.md).

The machine then holds the TCP turned by the thickness plane's estimate for the rest of
the run (``SpiralMachine.tcp_turn_rad``), and from FEEL's end takes the tip where the
estimates put it (``SpiralMachine.tip_t``: straight below the TCP once the plug is upright), so
that SEARCH's pattern is centred on the tip itself; SEARCH goes on with the press settled anew
(``felt``: the TCP's first move, pressed, takes the tip to the pattern's point; without an
estimate, ``no_flat_face``, upright and the nominal grasp as before). With ``site_m``, the
touch and the rock are that far from the nominal opening along its y, where the whole face
stands on the board (at the pattern's start the face may lie across the opening's rim,
and the rim's edges make steps of their own), and FEEL ends with a **lift** to the hover
there; SEARCH then goes to its pass's start and touches again. The face lies flat on the
board, so the angle is the plug's tilt from the board's normal: the receptacle's axis. Each
pair of legs' flat angle, kept or not, is published with the tip's offset it implies, the
plug's length times the sine of the tilt (``SpiralMachine.in_hand_estimates``); the kept
ones give the trial's ``tip_y_est_m`` and ``tip_x_est_m``. The rock does not see the plug's
offset across its width in the grasp (up to 1 mm in the scene); the machine takes it from the
grasp's imprint on the gel (controller/insertion/imprint.py).
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass, field
from enum import Enum
from typing import TYPE_CHECKING

import numpy as np

from controller.insertion.interface import Command, GraspPlane, InHandEstimate, Observation, Phase
from controller.insertion.phases.stage import Staged
from controller.insertion.spiral.spiral_search import SearchStage, SearchState
from core.config import Config, config_dataclass, number

if TYPE_CHECKING:
    from controller.insertion.spiral.spiral_machine import SpiralMachine


@config_dataclass
class RockSettings(Config):
    """The task's ``touch_spiral.rock:`` (see the module doc). ``enabled``; ``at_pass``: the
    SEARCH pass (0: the first) at whose touch FEEL runs;
    ``rock_speed_rad_s``: the TCP's turn about T x; ``rock_max_rad``: as far each way from
    upright; ``window``: frames each side of a step; ``min_step_nm``: the smallest torque step
    (N*m) that counts as the face turning flat; ``agree_rad``: the two sweeps' flat angles
    agree within this; ``site_m``: FEEL's touch this far (m) from the nominal opening along
    the opening's y, on the board clear of it (0: at the pass's own touch); ``width``: rock
    about T y too, for the tilt in the width plane."""

    enabled: bool = False
    at_pass: int = number(0, 100, default=0)
    rock_speed_rad_s: float = number(0.01, 1.0, default=0.15)
    rock_max_rad: float = number(0.01, 0.3, default=0.12)
    window: int = number(1, 20, default=3)
    min_step_nm: float = number(0.0, 0.1, default=0.0008)
    agree_rad: float = number(0.001, 0.2, default=0.03)
    site_m: float = number(0.0, 0.05, default=0.0)
    width: bool = False


class FeelStage(Enum):
    """FEEL's sub-stages, in order."""

    ROCK = "rock"  # toward +rock_max_rad about T x
    ROCK_BACK = "rock_back"  # toward -rock_max_rad
    ROCK_AGAIN = "rock_again"  # toward +rock_max_rad again, when the first leg had no step
    TURN = "turn"  # to the estimate (or upright) at ``rotate_speed_rad_s``, the press held
    WIDTH_ROCK = "width_rock"  # with ``width``: the same about T y
    WIDTH_ROCK_BACK = "width_rock_back"
    WIDTH_ROCK_AGAIN = "width_rock_again"
    WIDTH_TURN = "width_turn"
    LIFT = "lift"  # at the site (``site_m``): up to the hover before SEARCH goes on


@dataclass(frozen=True)
class RockPlane:
    """One plane FEEL rocks in: the TCP turned about T's ``axis`` (0: x, the thickness
    plane; 1: y, the width plane), its three legs and its turn (sub-stages), and its name in
    ``InHandEstimate.plane``."""

    axis: int
    legs: tuple[FeelStage, FeelStage, FeelStage]
    turn: FeelStage
    name: GraspPlane


THICKNESS = RockPlane(
    0, (FeelStage.ROCK, FeelStage.ROCK_BACK, FeelStage.ROCK_AGAIN), FeelStage.TURN, "thickness"
)
WIDTH = RockPlane(
    1,
    (FeelStage.WIDTH_ROCK, FeelStage.WIDTH_ROCK_BACK, FeelStage.WIDTH_ROCK_AGAIN),
    FeelStage.WIDTH_TURN,
    "width",
)
_PLANE = {stage: plane for plane in (THICKNESS, WIDTH) for stage in (*plane.legs, plane.turn)}


@dataclass
class FeelState(Staged[FeelStage]):
    """FEEL so far: ``angles`` the TCP's rock angles about T x and T y (rad) at the last
    100 ticks (time s, about x, about y); ``sweeps`` each leg's (angle rad, torque about the
    plane's axis N*m) per new frame; ``frame_t_s`` the last frame's capture time taken."""

    angles: deque[tuple[float, float, float]] = field(default_factory=lambda: deque(maxlen=100))
    sweeps: dict[FeelStage, list[tuple[float, float]]] = field(default_factory=dict)
    frame_t_s: float = -math.inf


def enter(obs: Observation) -> FeelState:
    return FeelState(FeelStage.ROCK, obs.t_s)


def step(m: SpiralMachine, obs: Observation) -> Command:
    """See the module doc."""
    settings, state = m.rock, m.state(FeelState)
    assert settings is not None
    force = m.tared_force(obs)
    state.angles.append((obs.t_s, m.rock_angle_rad(obs, 0), m.rock_angle_rad(obs, 1)))
    m.fire(state.stage.value)
    if state.stage is FeelStage.LIFT:
        hover = m.tip_target(m.memory.s_m, m.config.hover_m)
        if m.reach(obs, hover):
            return _back_to_search(m, obs, SearchStage.TURN)  # to the pass's start
        return m.servo(obs, hover)
    plane = _PLANE[state.stage]
    if state.stage is plane.turn:
        target = m.rock_estimate(0) if plane is THICKNESS else None  # upright about T y
        if _ramp(m, plane.axis, 0.0 if target is None else target, m.config.rotate_speed_rad_s) \
                and m.turned(obs):  # fmt: skip
            if plane is THICKNESS and settings.width:
                state.stage = FeelStage.WIDTH_ROCK
                return m.pressed(obs, force)
            m.memory.press_z_m = None  # the press settles anew at the new tilt
            if settings.site_m > 0.0:
                state.stage = FeelStage.LIFT
                return m.hold()
            _back_to_search(m, obs, SearchStage.SWEEP)
        return m.pressed(obs, force)
    _take_frame(m, obs, state, plane)
    leg = plane.legs.index(state.stage)
    goal = -settings.rock_max_rad if leg == 1 else settings.rock_max_rad
    angle = state.angles[-1][1 + plane.axis]
    ramped = _ramp(m, plane.axis, goal, settings.rock_speed_rad_s)
    if ramped and abs(angle - goal) <= m.config.turn_tol_rad:
        if leg == 0:
            state.stage = plane.legs[1]
        else:
            legs = [state.sweeps.get(stage, []) for stage in plane.legs[leg - 1 : leg + 1]]
            m.set_rock_estimate(plane.axis, _estimate(m, obs, legs, settings, plane))
            found = m.rock_estimate(plane.axis) is not None
            state.stage = plane.turn if found or leg == 2 else plane.legs[2]
    return m.pressed(obs, force)


def _back_to_search(m: SpiralMachine, obs: Observation, stage: SearchStage) -> Command:
    """FEEL over: SEARCH goes on at ``stage`` (``felt``, or ``no_flat_face`` without an
    estimate in either plane)."""
    felt = m.rock_estimate(0) is not None or m.rock_estimate(1) is not None
    m.go(obs, Phase.SEARCH, "felt" if felt else "no_flat_face")
    m.state(SearchState).stage = stage
    return m.hold()


def _ramp(m: SpiralMachine, axis: int, target_rad: float, speed_rad_s: float) -> bool:
    """The commanded turn about T's ``axis`` one tick nearer ``target_rad``; True once
    there."""
    current = m.tcp_turn_rad[axis]
    limit = speed_rad_s * m.tick_s
    m.tcp_turn_rad[axis] = current + max(-limit, min(limit, target_rad - current))
    return abs(target_rad - m.tcp_turn_rad[axis]) <= 1e-9


def _take_frame(m: SpiralMachine, obs: Observation, state: FeelState, plane: RockPlane) -> None:
    """A new frame's torque about the plane's axis with the rock angle at its capture time,
    into the present leg's sweep."""
    torque_t = m.reading.torque_t()
    if obs.wrench is None or torque_t is None or obs.wrench.t_s <= state.frame_t_s:
        return
    state.frame_t_s = obs.wrench.t_s
    angle = angle_at(((t, a[plane.axis]) for t, *a in state.angles), obs.wrench.t_s)
    sweep = state.sweeps.setdefault(state.stage, [])
    sweep.append((angle, float(torque_t[plane.axis])))


def angle_at(angles: Iterable[tuple[float, float]], t_s: float) -> float:
    """The rock angle (rad) at ``t_s``, interpolated in the ticks' (time, angle); the
    nearest end's outside them."""
    times, values = zip(*angles, strict=True)
    return float(np.interp(t_s, times, values))


def sweep_step(samples: list[tuple[float, float]], window: int) -> tuple[float, float] | None:
    """The largest torque step of a sweep (``samples``: (angle rad, torque N*m) in the
    sweep's order): (the angle between the two frames either side of it, the step's size
    N*m, the mean of ``window`` frames after less before); None with too few frames."""
    if len(samples) < 2 * window:
        return None
    torques = np.array([t for _, t in samples])
    best: tuple[float, float] | None = None
    for i in range(window, len(samples) - window + 1):
        step = float(np.mean(torques[i : i + window]) - np.mean(torques[i - window : i]))
        if best is None or abs(step) > abs(best[1]):
            best = (0.5 * (samples[i - 1][0] + samples[i][0]), step)
    return best


def flat_candidate(
    sweeps: list[list[tuple[float, float]]], settings: RockSettings
) -> tuple[float, bool] | None:
    """The tilt about T x (rad) at which the tip's face lies flat as two legs give it (the
    mean angle of their steps; ``sweeps``: the legs, in opposite directions) and whether it
    passes the checks (both steps at least ``min_step_nm``, the angles within
    ``agree_rad``); None when a leg has too few frames for a step."""
    angles, kept = [], True
    for samples in sweeps:
        step = sweep_step(samples, settings.window)
        if step is None:
            return None
        kept = kept and not abs(step[1]) < settings.min_step_nm
        angles.append(step[0])
    kept = kept and not max(angles) - min(angles) > settings.agree_rad
    return float(np.mean(angles)), kept


def flat_angle(sweeps: list[list[tuple[float, float]]], settings: RockSettings) -> float | None:
    """The tilt about T x (rad) at which the tip's face lies flat (``flat_candidate``), or
    None (a leg without a step, a step too small, or the legs disagree)."""
    candidate = flat_candidate(sweeps, settings)
    return candidate[0] if candidate is not None and candidate[1] else None


def _estimate(
    m: SpiralMachine,
    obs: Observation,
    sweeps: list[list[tuple[float, float]]],
    settings: RockSettings,
    plane: RockPlane,
) -> float | None:
    """The legs' flat angle (the TCP's turn about the plane's axis) if it passes its checks
    (``flat_angle``), else None; any candidate, kept or not, is published as the machine's
    in-hand estimate (``SpiralMachine.in_hand_estimates``: the plug's tilt in the plane and
    the tip's offset it implies, ``SpiralMachine.grasp_tilt_of_turn`` and
    ``SpiralMachine.tip_offset_of_tilt``)."""
    candidate = flat_candidate(sweeps, settings)
    if candidate is None:
        return None
    turn, kept = candidate
    tilt = m.grasp_tilt_of_turn(plane.axis, turn)
    m.publish_in_hand(InHandEstimate(
        obs.t_s, plane.name, tilt, m.tip_offset_of_tilt(plane.axis, tilt), "rock", kept
    ))  # fmt: skip
    return turn if kept else None
