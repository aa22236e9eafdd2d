"""SEARCH of the press-spiral machine, in passes (``plan_passes``): one per yaw offset
(``yaw_offsets``), or, with ``inner_half_width_m``, the spiral's inner part at every yaw and
then its outer part at every yaw. Each pass:

* **tare**: still at ``hover_m`` above the board for ``tare_s``; the mean force over the
  readings is the sensor's zero (the F/T sensor drifts; the tactile reading has none while
  the estimator re-zeroes);
* **touch**: down at ``descend_speed_m_s`` until the tared upward force reaches
  ``touch_force_n``; the TCP ``fall_in_m`` below where the tip would meet the nominal board
  first, the force still under ``fall_in_force_n``, means the plug went into the opening on
  the way down (INSERT, ``fell_in``, the nominal board's height taken as the press's); with
  ``rock`` on, the touch of pass ``rock.at_pass`` first finds the plug's tilt in the hand
  (FEEL, ``touched``: spiral_feel.py), and the sweep goes on from FEEL;
* **sweep**: the pattern at ``sweep_speed_m_s`` while the admittance holds the press; the
  press's height (the TCP's when the force first settles within ``settle_band`` of the
  press) is the reference. A force under ``catch_ratio`` x the press pauses the pattern
  (**probe**; with ``rewind``, first back to where it was at the time the reading
  describes, once per stretch) and the admittance lowers the TCP: the tip ``catch_drop_m``
  below its height at the press is caught (INSERT); the force back at the press, or
  ``probe_s``, and the pattern goes on; with ``near_miss`` on, a jump of the tilt torques
  (the face across the opening's rim) that the sweep passes without a catch sends the
  pattern back over that stretch on the ring half a pitch outside its own (**retrace**,
  spiral_near_miss.py), probing as the sweep does, and then on along its own ring from
  where the sweep had reached. The TCP ``fall_in_m`` below its height at the pass's touch,
  the force under ``catch_ratio`` x the press, means the plug sank into the opening while
  the admittance sought the press (INSERT, ``fell_in``, the touch's height taken as the
  press's): the press never settles there, and without this the pattern stood probing at
  the arm's floor until the time ran out. With ``sink_m``, the tip that far below its height
  at the press while sweeping has sunk in with no force drop (the walls bear the press while
  the pattern drags the plug in the opening's mouth): INSERT, ``sank``;
* **rise**: at the pass's end, up to the hover, then **turn** to the next pass's start and
  yaw (or RELEASE after the last, ``pattern_done``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from enum import Enum
from typing import TYPE_CHECKING

import numpy as np

from controller.insertion.interface import Command, Observation, Phase
from controller.insertion.phases.stage import Staged
from controller.insertion.search_path import SearchPattern

if TYPE_CHECKING:
    from controller.insertion.spiral.spiral_config import SpiralConfig
    from controller.insertion.spiral.spiral_machine import SpiralMachine


@dataclass(frozen=True)
class SearchPass:
    """One pass of SEARCH: the tool's yaw offset from the nominal opening's (rad), the
    stretch of the pattern's path it sweeps, from ``start_m`` to ``end_m`` (path length, m),
    and the pattern's turn about the opening's centre (``pattern_turn_rad``, rad, about B z)."""

    yaw_offset_rad: float
    start_m: float
    end_m: float
    pattern_turn_rad: float = 0.0


def plan_passes(config: SpiralConfig) -> tuple[SearchPass, ...]:
    """SEARCH's passes in order: the whole pattern at each of ``yaw_offsets`` in turn, or,
    with ``inner_half_width_m``, the spiral out to it at each yaw, then the rest at each yaw
    (a tip near the opening's centre is then found at every yaw before the far ring is
    swept at any); with ``interleave``, the passes at every other yaw step (the offsets
    alternate: 0, +1, -1, +2, -2, ... steps) turned by half a turn, so that neighbouring yaws'
    rings interleave."""
    whole = SearchPattern(config.pattern, config.pitch_m, config.half_width_m).length_m
    stretches = [(0.0, whole)]
    if config.inner_half_width_m > 0.0:
        inner = SearchPattern("spiral", config.pitch_m, config.inner_half_width_m).length_m
        stretches = [(0.0, inner), (inner, whole)]
    turns = (0.0, math.pi) if config.interleave and config.pattern == "spiral" else (0.0,)
    return tuple(
        SearchPass(yaw, start, end, turns[((k + 1) // 2) % len(turns)])
        for start, end in stretches
        for k, yaw in enumerate(config.yaw_offsets)
    )


class SearchStage(Enum):
    """SEARCH's sub-stages (see the module doc)."""

    TARE = "tare"
    TOUCH = "touch"
    SWEEP = "sweep"
    PROBE = "probe"
    RETRACE = "retrace"
    RISE = "rise"
    TURN = "turn"


@dataclass
class SearchState(Staged[SearchStage]):
    """SEARCH's sub-stage, and the forces taken for the tare so far (N)."""

    tare_n: list[float] = field(default_factory=list)


def enter(obs: Observation) -> SearchState:
    return SearchState(SearchStage.TARE, obs.t_s)


def step(m: SpiralMachine, obs: Observation) -> Command:
    """See the module doc."""
    cfg, state, run = m.config, m.state(SearchState), m.memory
    if state.stage is SearchStage.TARE:  # over readings only
        if m.read_force(obs):
            state.tare_n.append(m.force_n)
        if obs.t_s - state.since_t_s >= cfg.tare_s and state.tare_n:
            run.bias_n, run.tared, run.press_z_m = float(np.mean(state.tare_n)), True, None
            run.touch_z_m = None
            state.tare_n, state.stage = [], SearchStage.TOUCH
        m.fire("tare")
        return m.servo(obs, m.tip_target(run.s_m, cfg.hover_m))
    force = m.tared_force(obs)
    if state.stage is SearchStage.TOUCH:
        m.fire("touch")
        if m.near_misses is not None:  # each pass's sweep takes its own baseline
            m.near_misses.reset()
            run.near_miss_m = None
        if force >= cfg.touch_force_n:
            run.touch_z_m = obs.arm.tcp.xyz_m[2]
            if m.rock is not None and not m.felt and run.pass_index >= m.rock.at_pass:
                m.felt = True
                m.go(obs, Phase.FEEL, "touched")
                return m.hold()
            state.next(SearchStage.SWEEP, obs.t_s)
            return m.pressed(obs, force)
        board_z = m.board_tcp_z_m()
        if obs.arm.tcp.xyz_m[2] < board_z - cfg.fall_in_m and force < cfg.fall_in_force_n:
            run.press_z_m = board_z
            m.go(obs, Phase.INSERT, "fell_in")
            return m.hold()
        return m.descend(obs, cfg.descend_speed_m_s)
    if state.stage in (SearchStage.SWEEP, SearchStage.PROBE, SearchStage.RETRACE):
        return _sweep_or_probe(m, obs, state, force)
    if state.stage is SearchStage.TURN:  # to the next pass's start, at its yaw
        target = m.tip_target(m.search_pass.start_m, cfg.hover_m)
        if m.reach(obs, target) and m.turned(obs):
            state.next(SearchStage.TARE, obs.t_s)
        m.fire("turn")
        return m.servo(obs, target)
    target = m.tip_target(run.s_m, cfg.hover_m)  # RISE
    m.fire("rise")
    if m.reach(obs, target):
        if run.pass_index + 1 >= len(m.passes):
            m.go(obs, Phase.RELEASE, "pattern_done")
            return m.hold()
        run.pass_index += 1
        run.s_m = m.search_pass.start_m
        state.stage = SearchStage.TURN
    return m.servo(obs, target)


def _sweep_or_probe(
    m: SpiralMachine, obs: Observation, state: SearchState, force: float
) -> Command:
    cfg, run = m.config, m.memory
    touch_z = run.touch_z_m
    if (
        touch_z is not None
        and force < cfg.catch_ratio * cfg.press_force_n
        and obs.arm.tcp.xyz_m[2] < touch_z - cfg.fall_in_m
    ):
        run.press_z_m = touch_z
        m.go(obs, Phase.INSERT, "fell_in")
        return m.hold()
    if run.press_z_m is None and abs(force - cfg.press_force_n) <= (
        cfg.settle_band * cfg.press_force_n
    ):
        run.press_z_m = obs.arm.tcp.xyz_m[2]
    if state.stage is SearchStage.PROBE:
        m.fire("probe")
        if run.press_z_m is not None and m.catch_drop_m(obs, force) >= cfg.catch_drop_m:
            m.go(obs, Phase.INSERT, "caught")
            return m.hold()
        if force >= cfg.press_force_n or obs.t_s - state.since_t_s >= cfg.probe_s:
            retracing = run.retrace_until_m is not None
            state.stage = SearchStage.RETRACE if retracing else SearchStage.SWEEP
        return m.pressed(obs, force)
    if run.press_z_m is not None and force < cfg.catch_ratio * cfg.press_force_n:
        state.next(SearchStage.PROBE, obs.t_s)
        if cfg.rewind and run.s_m > run.rewound_to_m:
            run.rewound_to_m = run.s_m
            run.s_m = run.s_at(m.force_t_s)
        m.fire("probe")
        return m.pressed(obs, force)
    if (
        state.stage is SearchStage.SWEEP
        and run.press_z_m is not None
        and cfg.sink_m > 0.0
        and m.catch_drop_m(obs, force) >= cfg.sink_m
    ):
        m.go(obs, Phase.INSERT, "sank")
        return m.hold()
    if state.stage is SearchStage.SWEEP and run.press_z_m is not None:
        near_miss = m.near_miss_at(obs)
        if near_miss is not None and run.near_miss_m is None:
            run.near_miss_m = run.s_at(near_miss[0])
            run.near_miss_side_b = near_miss[1]
        if run.near_miss_m is not None and _retrace_due(m):
            state.stage = SearchStage.RETRACE
    if state.stage is SearchStage.RETRACE and not run.retrace_started:
        m.fire("retrace")  # back to its start, pressed, before it sweeps
        run.retrace_started = m.reach_xy(obs, m.tip_target(run.s_m, 0.0))
        return m.pressed(obs, force)
    run.s_m += cfg.sweep_speed_m_s * m.tick_s
    run.s_history.append((obs.t_s, run.s_m))
    if state.stage is SearchStage.RETRACE:
        m.fire("retrace")
        assert run.retrace_until_m is not None and m.near_misses is not None
        if run.s_m >= run.retrace_until_m:
            run.s_m, run.retrace_until_m = run.resume_m, None
            m.near_misses.reset()  # the same rim once more is no new near miss
            state.stage = SearchStage.SWEEP
        return m.pressed(obs, force, moving=True)
    if run.s_m >= m.search_pass.end_m:
        state.stage = SearchStage.RISE
    m.fire("sweep")
    return m.pressed(obs, force, moving=True)


def _retrace_due(m: SpiralMachine) -> bool:
    """Begin the retrace of the near miss at ``near_miss_m`` once the sweep has gone
    ``ahead_m`` past it without a catch, unless the pass has had its ``per_pass`` or comes
    before ``from_pass``: from ``back_m`` before it (reached first, pressed) to ``ahead_m``
    after it, on the ring ``outward_m`` outside, or inside with ``toward_side`` where the side
    the near miss named points toward the pattern's centre; the sweep then resumes where it
    had reached."""
    detector, run, there = m.near_misses, m.memory, m.memory.near_miss_m
    assert detector is not None and there is not None
    settings = detector.settings
    if run.s_m < there + settings.ahead_m:
        return False
    run.near_miss_m = None
    detector.reset()  # the same rim retraced is no new near miss
    done = run.retraces.get(run.pass_index, 0)
    if done >= settings.per_pass or run.pass_index < settings.from_pass:
        return False
    run.retraces[run.pass_index] = done + 1
    radial_b = m.tip_target(there, 0.0)[:2] - np.array([m.hole.x_m, m.hole.y_m])
    side = run.near_miss_side_b
    run.retrace_inward = bool(
        settings.toward_side and side is not None and float(side @ radial_b) < 0.0
    )
    run.resume_m, run.retrace_until_m = run.s_m, there + settings.ahead_m
    run.s_m = max(m.search_pass.start_m, there - settings.back_m)
    run.retrace_started = False
    return True
