"""The press-spiral machine: the product's machine by touch (``dipole``, and ``fingervision``,
``zero_torque``, ``torque_only`` and ``oracle`` on other wrench sources; settings: the task's
``touch_spiral:`` section), on the tactile estimate's axial force
(controller/insertion/force_reading.py), and the same search on the arm's F/T sensor, the
strongest search an integrator would build without touch (``blind``; settings ``blind:``).

It grasps, moves the plug upright above the nominal opening and, for each of SEARCH's
passes (a yaw and a stretch of the pattern: ``spiral_search.plan_passes``), tares the force
at the hover, touches the board, sweeps the pattern pressed and, where the force drops,
probes, pushes and releases (each phase's module says how: spiral_grasp.py,
spiral_approach.py, spiral_search.py, spiral_insert.py, spiral_release.py).
A trial scores it as every controller (evaluation/trials/trial.py): DONE with the tip at the
depth at some time.

Phases: GRASP -> APPROACH -> SEARCH <-> INSERT -> RELEASE -> RETRACT -> DONE. Each tick,
in this order: a device fault ends the run (FAILED, ``device_fault``); the e-stop button
latches ESTOP; an operator in control takes over (TELEOP; spiral_overrides.py says where
autonomy resumes); an arm without a force reading ends it (``device_fault``, its rule ``no_force``:
the arm file's ``ft_sensor`` is off), as does the budget ``timeout_s`` of autonomous time
(``timeout``); with the plug in hand (APPROACH, SEARCH, INSERT), the gripper no longer
holding (``slip``; not the estimate's slip flags: their false alarms while the plug sweeps
the board pressed would end runs that insert), and the tared force over ``tared_force_limit_n``
or the TCP tilted more than ``tilt_limit_rad`` (``limit_exceeded``); then the phase's step.
The table and every phase's sub-stages are data (``SPIRAL``), checked when the machine is
built; every command names the rule (``Command.rule``, ``phase.rule``) and the sub-stage
(``Command.stage``) that decided it.
"""

from __future__ import annotations

import dataclasses
import math
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import Enum
from typing import Any, TypeVar

import numpy as np
from scipy.spatial.transform import Rotation

from controller.insertion.definition import Definition, Edge, check_definition
from controller.insertion.force_reading import ArmForce, ForceReading
from controller.insertion.grasp_estimate import GraspEstimate, tilt_tip_offset_m
from controller.insertion.imprint import FaceOffset
from controller.insertion.interface import (
    Command,
    FailureReason,
    InHandEstimate,
    Observation,
    Phase,
    Transition,
)
from controller.insertion.motion import bounded_twist, pivot_twist, rotation_error
from controller.insertion.phases.overrides import EstopStage, TeleopStage, TerminalStage
from controller.insertion.search_path import SearchPattern
from controller.insertion.spiral import (
    spiral_approach as approach,
)
from controller.insertion.spiral import (
    spiral_feel as feel,
)
from controller.insertion.spiral import (
    spiral_grasp as grasp,
)
from controller.insertion.spiral import (
    spiral_insert as insert,
)
from controller.insertion.spiral import (
    spiral_near_miss as near_miss,
)
from controller.insertion.spiral import (
    spiral_overrides as overrides,
)
from controller.insertion.spiral import (
    spiral_release as release,
)
from controller.insertion.spiral import (
    spiral_search as search,
)
from controller.insertion.spiral.spiral_config import SpiralConfig
from controller.insertion.spiral.torque_servo import TorqueServo
from core.devices import Twist
from core.spatial import clamp_norm, remembers_recent, rotation_from_rpy, tilt_of_rotation
from core.task_geometry import HolePose, PlugGeometry

LEAD_S = 0.01  # the sweep's velocity is the target's over this time ahead, s
HISTORY_TICKS = 100  # the sweep's (time, length) kept for a rewind: 1 s at 100 Hz
NO_FORCE = "no_force"  # the FAILED transition's rule when the arm reports no force

F = FailureReason
_WORKING = (
    Phase.GRASP, Phase.APPROACH, Phase.SEARCH, Phase.FEEL, Phase.INSERT, Phase.RELEASE,
    Phase.RETRACT,
)  # fmt: skip
# the plug in hand, near the board
_HOLDING = (Phase.APPROACH, Phase.SEARCH, Phase.FEEL, Phase.INSERT)
_RESUMED = (Phase.GRASP, Phase.RETRACT)  # where autonomy resumes (overrides.resume)


def _edges(sources: tuple[Phase, ...], target: Phase, *guards: str) -> tuple[Edge, ...]:
    return tuple(Edge(source, target, guard) for source in sources for guard in guards)


@remembers_recent(8)
def _untilted_at(yaw_rad: float) -> Rotation:
    """Upright at ``yaw_rad`` (T2B): z_T down, x_T at the yaw."""
    return Rotation.from_euler("z", yaw_rad) * Rotation.from_euler("x", math.pi)


@remembers_recent(8)
def _upright_at(yaw_rad: float, turn_x_rad: float, turn_y_rad: float) -> Rotation:
    """Upright at ``yaw_rad``, turned about T x, then T y, by FEEL's turn (T2B)."""
    upright = _untilted_at(yaw_rad) * Rotation.from_euler("x", turn_x_rad)
    if turn_y_rad:
        upright = upright * Rotation.from_euler("y", turn_y_rad)
    return upright


@remembers_recent(8)
def _plug_axis_t(turn_x_rad: float, turn_y_rad: float) -> np.ndarray:
    """The plug's unit axis in T, T z turned back by the grasp's turn (about T x, then T y).
    Read only: the caller scales it into a new array."""
    axis = Rotation.from_euler("x", -turn_x_rad).apply([0.0, 0.0, 1.0])
    if turn_y_rad:
        axis = Rotation.from_euler("y", -turn_y_rad).apply(axis)
    axis.flags.writeable = False
    return axis


SPIRAL = Definition(
    phases=(*_WORKING, Phase.TELEOP, Phase.ESTOP, Phase.DONE, Phase.FAILED),
    initial=Phase.GRASP,
    terminal=(Phase.DONE, Phase.FAILED),
    edges=(
        Edge(Phase.GRASP, Phase.APPROACH, "grasped"),
        Edge(Phase.APPROACH, Phase.SEARCH, "above_the_opening"),
        Edge(Phase.SEARCH, Phase.INSERT, "caught"),
        Edge(Phase.SEARCH, Phase.INSERT, "fell_in"),
        Edge(Phase.SEARCH, Phase.INSERT, "sank"),
        Edge(Phase.SEARCH, Phase.FEEL, "touched"),
        Edge(Phase.FEEL, Phase.SEARCH, "felt"),
        Edge(Phase.FEEL, Phase.SEARCH, "no_flat_face"),
        Edge(Phase.INSERT, Phase.SEARCH, "jammed"),
        Edge(Phase.INSERT, Phase.RELEASE, "bottomed"),
        Edge(Phase.SEARCH, Phase.RELEASE, "pattern_done"),
        Edge(Phase.RELEASE, Phase.RETRACT, "released"),
        Edge(Phase.RETRACT, Phase.DONE, "retracted"),
        *_edges(_WORKING, Phase.FAILED, F.TIMEOUT.value, F.DEVICE_FAULT.value),
        *_edges(_HOLDING, Phase.FAILED, F.SLIP.value, F.LIMIT_EXCEEDED.value),
        *_edges(_WORKING, Phase.TELEOP, "operator_takeover"),
        *_edges((*_WORKING, Phase.TELEOP), Phase.ESTOP, "estop"),
        *_edges((Phase.TELEOP,), _RESUMED[0], "hand_back"),
        *_edges((Phase.TELEOP,), _RESUMED[1], "hand_back"),
        *_edges((Phase.ESTOP,), _RESUMED[0], "estop_acknowledged"),
        *_edges((Phase.ESTOP,), _RESUMED[1], "estop_acknowledged"),
        Edge(Phase.ESTOP, Phase.TELEOP, "estop_acknowledged"),
        *_edges((Phase.TELEOP, Phase.ESTOP), Phase.FAILED, F.DEVICE_FAULT.value),
    ),
    stages={
        Phase.GRASP: tuple(grasp.GraspStage),
        Phase.APPROACH: tuple(approach.ApproachStage),
        Phase.SEARCH: tuple(search.SearchStage),
        Phase.FEEL: tuple(feel.FeelStage),
        Phase.INSERT: tuple(insert.InsertStage),
        Phase.RELEASE: tuple(release.ReleaseStage),
        Phase.RETRACT: tuple(release.RetractStage),
        Phase.TELEOP: (TeleopStage.OPERATOR,),
        Phase.ESTOP: (EstopStage.HOLD,),
        Phase.DONE: (TerminalStage.HOLD,),
        Phase.FAILED: (TerminalStage.HOLD,),
    },
)


@dataclass
class TerminalState:
    """DONE's or FAILED's one sub-stage."""

    stage: TerminalStage = TerminalStage.HOLD


@dataclass
class SearchMemory:
    """What SEARCH and INSERT share through the run: the pass (``pass_index`` into the
    machine's ``passes``), the pattern's path length swept in it (``s_m``, m) and its recent
    history (time s, length m) for a rewind, the length at the last rewound probe
    (``rewound_to_m``), the tared zero (``bias_n``, N; ``tared`` once one is taken), the
    TCP's height at the settled press (``press_z_m``, B, m; None until the press settles
    after a tare) and at the pass's touch (``touch_z_m``, B, m; None until it touches), the
    place of a near miss not yet retraced (``near_miss_m``, path length, m; None without
    one) and the side it named (``near_miss_side_b``, a unit vector in B's x-y plane), and a
    retrace's: where it ends (``retrace_until_m``, m; None outside one) and the sweep resumes
    (``resume_m``), whether its start has been reached (``retrace_started``), whether its
    ring lies inside the pattern's (``retrace_inward``) and the retraces made in each pass so
    far (``retraces``, by pass index)."""

    pass_index: int = 0
    s_m: float = 0.0
    s_history: deque[tuple[float, float]] = field(
        default_factory=lambda: deque(maxlen=HISTORY_TICKS)
    )
    rewound_to_m: float = -math.inf
    bias_n: float = 0.0
    tared: bool = False
    press_z_m: float | None = None
    touch_z_m: float | None = None
    near_miss_m: float | None = None
    near_miss_side_b: np.ndarray | None = None
    retrace_until_m: float | None = None
    resume_m: float = 0.0
    retrace_started: bool = False
    retrace_inward: bool = False
    retraces: dict[int, int] = field(default_factory=dict)

    def s_at(self, t_s: float) -> float:
        """The pattern's swept length at time ``t_s`` (the earliest kept, if older)."""
        for t, s_m in reversed(self.s_history):
            if t <= t_s:
                return s_m
        return self.s_history[0][1] if self.s_history else self.s_m


_ENTER: dict[Phase, Callable[[Observation], Any]] = {
    Phase.GRASP: grasp.enter,
    Phase.APPROACH: approach.enter,
    Phase.SEARCH: search.enter,
    Phase.FEEL: feel.enter,
    Phase.INSERT: insert.enter,
    Phase.RELEASE: release.enter_release,
    Phase.RETRACT: release.enter_retract,
    Phase.TELEOP: overrides.enter_teleop,
    Phase.ESTOP: overrides.enter_estop,
    Phase.DONE: lambda obs: TerminalState(),
    Phase.FAILED: lambda obs: TerminalState(),
}
_STEP: dict[Phase, Callable[[SpiralMachine, Observation], Command]] = {
    Phase.GRASP: grasp.step,
    Phase.APPROACH: approach.step,
    Phase.SEARCH: search.step,
    Phase.FEEL: feel.step,
    Phase.INSERT: insert.step,
    Phase.RELEASE: release.release,
    Phase.RETRACT: release.retract,
}
StateT = TypeVar("StateT")


class SpiralMachine:
    """The press-spiral machine (see the module doc); a ``Machine`` for the control loop.
    ``reading``: where the force comes from (the arm's F/T sensor by default); ``torque_servo``:
    INSERT's yield to the reading's torques while pushing (none: the plug held at the pass's
    orientation); ``rock``: FEEL's settings; ``near_misses``: the sweep's near misses in the
    reading's tilt torques (none: not looked for); ``face``: the plug's offset across the
    fingers from its imprint on the gel (none: the nominal grasp's 0)."""

    def __init__(
        self,
        config: SpiralConfig,
        plug: PlugGeometry,
        hole: HolePose,
        reading: ForceReading | None = None,
        torque_servo: TorqueServo | None = None,
        rock: feel.RockSettings | None = None,
        near_misses: near_miss.NearMissSettings | None = None,
        face: FaceOffset | None = None,
    ) -> None:
        check_definition(SPIRAL)
        self.face = face
        # the plug's offset across the fingers (along T x, m) from its imprint, None before
        # one is measured
        self.face_offset_m: float | None = None
        self.config, self.plug, self.hole = config, plug, hole
        self.torque_servo = torque_servo
        self.rock = rock if rock is not None and rock.enabled else None
        self.near_misses = (
            near_miss.NearMissDetector(near_misses)
            if near_misses is not None and near_misses.enabled
            else None
        )
        # the TCP's commanded turn about T x and T y from upright (FEEL; about T y only
        # while FEEL rocks), rad
        self.tcp_turn_rad = [0.0, 0.0]
        # FEEL's flat angles: the TCP's turns about T x and T y that set the plug upright, rad
        self.turn_estimate_rad: list[float | None] = [None, None]
        # the turns that the tip's place is taken at (``tip_t``): FEEL's estimates once FEEL
        # is over, the nominal grasp's 0 before, rad
        self.grasp_turn_rad = [0.0, 0.0]
        self.felt = False  # FEEL has run
        self.reading = reading if reading is not None else ArmForce(config.force_window)
        self.memory = SearchMemory()
        self.force_n = 0.0  # the reading's last force (N) and the time it describes (s)
        self.force_t_s = 0.0
        self.tick_s = 0.0  # time since the previous tick, s
        self._pattern = SearchPattern(config.pattern, config.pitch_m, config.half_width_m)
        self.passes = search.plan_passes(config)
        self._phase = Phase.GRASP
        self._state: Any = None  # the present phase's state (its module's dataclass)
        self._transitions: list[Transition] = []
        self._in_hand: list[InHandEstimate] = []  # FEEL's estimates, kept or not
        self._start_t_s: float | None = None
        self._last_t_s = 0.0
        self._override_s = 0.0  # time spent in TELEOP and ESTOP, s
        self.released = False  # RELEASE was entered
        self._decided: tuple[Phase, Enum, str] | None = None  # this tick's sub-stage, rule

    # -- the Machine protocol ------------------------------------------------------------

    @property
    def phase(self) -> Phase:
        return self._phase

    @property
    def stage(self) -> Enum:
        """The present phase's sub-stage (GRASP's start before the first step)."""
        return grasp.GraspStage.START if self._state is None else self._state.stage

    @property
    def transitions(self) -> tuple[Transition, ...]:
        return tuple(self._transitions)

    @property
    def in_hand_estimates(self) -> tuple[InHandEstimate, ...]:
        """FEEL's estimates of the plug's tilt in the thickness plane, kept or not, in the
        order made (spiral_feel.py)."""
        return tuple(self._in_hand)

    def publish_in_hand(self, estimate: InHandEstimate) -> None:
        """Add ``estimate`` to ``in_hand_estimates`` (it commands nothing)."""
        self._in_hand.append(estimate)

    @property
    def tilt_x_estimate_rad(self) -> float | None:
        """FEEL's tilt of the plug about T x (the thickness plane; the TCP's turn that sets it
        upright, rad), None without one: the trial's ``grasp_tilt_thickness_est_rad``."""
        return self.turn_estimate_rad[0]

    @property
    def grasp(self) -> GraspEstimate | None:
        """FEEL's width-plane estimate (the tilt about T y, the tip toward +T x positive),
        None without one: the trial's ``grasp_tilt_est_rad`` and ``tip_x_est_m``."""
        turn = self.turn_estimate_rad[1]
        return None if turn is None else GraspEstimate(-turn, self.plug.length_m)

    def rock_estimate(self, axis: int) -> float | None:
        """FEEL's flat angle about T's ``axis`` (0: x, 1: y; rad), None without one."""
        return self.turn_estimate_rad[axis]

    def set_rock_estimate(self, axis: int, turn_rad: float | None) -> None:
        """Keep FEEL's flat angle about T's ``axis`` (rad; None: none found)."""
        self.turn_estimate_rad[axis] = turn_rad

    @staticmethod
    def grasp_tilt_of_turn(axis: int, turn_rad: float) -> float:
        """The plug's tilt in the hand (rad; about T x with its tip toward +T y, about T y
        toward +T x: evaluation/trials/grasp_truth.py) that the TCP's turn ``turn_rad`` about
        T's ``axis`` sets upright: the turn itself about T x, its opposite about T y."""
        return turn_rad if axis == 0 else -turn_rad

    def tip_offset_of_tilt(self, axis: int, tilt_rad: float) -> float:
        """The tip's offset from the nominal (m; along T y for a tilt about T x, ``axis`` 0,
        along T x for one about T y) that a tilt ``tilt_rad`` of the plug in the hand implies
        (``grasp_estimate.tilt_tip_offset_m``), along T x with the plug's offset across the
        fingers (``face_offset_m``, 0 unread)."""
        offset = tilt_tip_offset_m(tilt_rad, self.plug.length_m)
        return offset if axis == 0 else offset + (self.face_offset_m or 0.0)

    @property
    def tip_y_estimate_m(self) -> float | None:
        """The tip's offset from the nominal along T y (m) implied by FEEL's tilt estimate
        about T x (``tilt_x_estimate_rad``; ``grasp_estimate.tilt_tip_offset_m``), None
        without one: the trial's ``tip_y_est_m``. The machine places the tip by the same estimate
        from FEEL's end (``tip_t``)."""
        if self.tilt_x_estimate_rad is None:
            return None
        return tilt_tip_offset_m(self.tilt_x_estimate_rad, self.plug.length_m)

    @property
    def tip_x_estimate_m(self) -> float | None:
        """The tip's offset from the nominal along T x (m) once FEEL has the width-plane tilt
        (``grasp``): the one that tilt implies plus the plug's offset across the fingers
        (``face_offset_m``, 0 unread); None before: the trial's ``tip_x_est_m``."""
        grasp = self.grasp
        return None if grasp is None else self.tip_offset_of_tilt(1, grasp.tilt_rad)

    def step(self, obs: Observation) -> Command:
        """One tick: the command for ``obs``, naming the rule and the sub-stage that decided
        it."""
        if self._state is None:
            self._state = _ENTER[self._phase](obs)
        self._decided = None
        command = self._decide(obs)
        phase, stage, rule = self._decided or (self._phase, self._state.stage, "")
        if stage not in SPIRAL.stages[phase]:
            raise RuntimeError(f"sub-stage {phase.name}.{stage.name} is not in the definition")
        return dataclasses.replace(command, rule=rule, stage=f"{phase.value}.{stage.value}")

    def _decide(self, obs: Observation) -> Command:
        if self._phase in (Phase.DONE, Phase.FAILED):
            self.fire("hold")
            return self.hold()
        if self._start_t_s is None:
            self._start_t_s = self._last_t_s = obs.t_s
        self.tick_s, self._last_t_s = obs.t_s - self._last_t_s, obs.t_s
        if obs.fault or obs.arm.error_code or obs.gripper.fault_code:
            return self._fail(obs, F.DEVICE_FAULT)
        if obs.teleop.estop and self._phase is not Phase.ESTOP:
            self.go(obs, Phase.ESTOP, "estop")
        if obs.teleop.in_control and self._phase in _WORKING:
            self.go(obs, Phase.TELEOP, "operator_takeover")
        if self._phase in (Phase.ESTOP, Phase.TELEOP):
            self._override_s += self.tick_s
            step = overrides.estop if self._phase is Phase.ESTOP else overrides.teleop
            return step(self, obs)
        if not self.reading.available(obs):
            return self._fail(obs, F.DEVICE_FAULT, NO_FORCE)
        if obs.t_s - self._start_t_s - self._override_s > self.config.timeout_s:
            return self._fail(obs, F.TIMEOUT)
        if self._phase in _HOLDING:
            if not obs.gripper.holding:
                return self._fail(obs, F.SLIP)
            if self._limit_exceeded(obs):
                return self._fail(obs, F.LIMIT_EXCEEDED)
        self._read_face(obs)
        return _STEP[self._phase](self, obs)

    def _read_face(self, obs: Observation) -> None:
        """Take the plug's offset across the fingers from its imprint when a new one is
        measured (the grasp's, a re-grasp's), and publish it (``method`` 'imprint': a tip
        offset along T x, no tilt)."""
        offset = None if self.face is None else self.face.read(obs)
        if offset is None or offset == self.face_offset_m:
            return
        self.face_offset_m = offset
        self.publish_in_hand(InHandEstimate(obs.t_s, "width", math.nan, offset, "imprint", True))

    def _limit_exceeded(self, obs: Observation) -> bool:
        """The tared force over ``tared_force_limit_n`` (once a tare is taken), or the TCP tilted
        more than ``tilt_limit_rad`` from straight down."""
        tilt = tilt_of_rotation(rotation_from_rpy(obs.arm.tcp.rpy_rad))
        tared_n = self.force_n - self.memory.bias_n
        tared = self.memory.tared and tared_n > self.config.tared_force_limit_n
        return bool(tilt > self.config.tilt_limit_rad or tared)

    # -- what the phases act through -------------------------------------------------------

    def state(self, kind: type[StateT]) -> StateT:
        """The present phase's state, of type ``kind`` (RuntimeError if it is not)."""
        if not isinstance(self._state, kind):
            raise RuntimeError(f"phase {self._phase.name} has no {kind.__name__}")
        return self._state

    def fire(self, rule: str) -> None:
        """Name the rule deciding this tick's command (``phase.rule``), in the present
        sub-stage."""
        self._decided = (self._phase, self._state.stage, f"{self._phase.value}.{rule}")

    def go(self, obs: Observation, target: Phase, guard: str, rule: str = "") -> None:
        """Move to ``target`` under ``guard`` (``rule``: which of the guard's rules fired);
        the tick's rule is the guard unless a phase named one. A retrace ends with its
        phase, and the near misses' baseline starts anew."""
        if not SPIRAL.allows(self._phase, target, guard):
            raise RuntimeError(f"spiral machine: no edge {self._phase} -> {target} ({guard})")
        if self._decided is None:
            self.fire(guard)
        self._transitions.append(Transition(obs.t_s, self._phase, target, guard, rule))
        self.memory.retrace_until_m = None
        self.memory.near_miss_m = None
        if self.near_misses is not None:
            self.near_misses.reset()
        if self._phase is Phase.FEEL:  # the tip's place, by the estimate from here on
            self.grasp_turn_rad = [turn or 0.0 for turn in self.turn_estimate_rad]
            if target is not Phase.SEARCH:  # cut short: no rock; upright about T y
                self.tcp_turn_rad = [self.grasp_turn_rad[0], 0.0]
        self._phase, self._state = target, _ENTER[target](obs)
        self.released = self.released or target is Phase.RELEASE

    def _fail(self, obs: Observation, reason: FailureReason, rule: str = "") -> Command:
        self.go(obs, Phase.FAILED, reason.value, rule)
        return self.hold()

    @staticmethod
    def hold() -> Command:
        """Still."""
        return Command(twist=Twist())

    @property
    def search_pass(self) -> search.SearchPass:
        """SEARCH's present pass."""
        return self.passes[self.memory.pass_index]

    # -- the force --------------------------------------------------------------------------

    def read_force(self, obs: Observation) -> bool:
        """Take the reading's newest force and its time, if it has one (True)."""
        reading = self.reading.read(obs)
        if reading is not None:
            self.force_n, self.force_t_s = reading
        return reading is not None

    def near_miss_at(self, obs: Observation) -> tuple[float, np.ndarray] | None:
        """The capture time (s) of the newest frame and the side it names (a unit vector in
        B's x-y plane, ``near_miss.side_named_b``) if its tilt torques jumped as a near miss
        does (spiral_near_miss.py), else None (and always without ``near_misses``)."""
        if self.near_misses is None or obs.wrench is None:
            return None
        jump_t = self.near_misses.jump(self.reading.torque_t(), obs.wrench.t_s)
        if jump_t is None:
            return None
        t2b = rotation_from_rpy(obs.arm.tcp.rpy_rad)
        return obs.wrench.t_s, near_miss.side_named_b(jump_t, t2b)

    def tared_force(self, obs: Observation) -> float:
        """The upward force on the tool (z in B, N) less the tare: the reading's newest (its
        last while it has none)."""
        self.read_force(obs)
        return self.force_n - self.memory.bias_n

    def tip_drop_m(self, obs: Observation, force: float) -> float:
        """How far the tip has gone below its height at the settled press, m: the TCP's drop
        less the wrist's extra compression (force above the press over its stiffness)."""
        press_z = self.memory.press_z_m
        assert press_z is not None  # set before any catch
        cfg = self.config
        tcp_drop = press_z - obs.arm.tcp.xyz_m[2]
        return tcp_drop - (force - cfg.press_force_n) / cfg.wrist_z_stiffness_n_m

    def catch_drop_m(self, obs: Observation, force: float) -> float:
        """The probe's drop (m): ``tip_drop_m``, or with ``catch_drop_from: tcp`` the same
        without crediting the wrist's extension under a force below the press."""
        if self.config.catch_drop_from == "tip":
            return self.tip_drop_m(obs, force)
        return self.tip_drop_m(obs, max(force, self.config.press_force_n))

    # -- where the tool goes ----------------------------------------------------------------

    def _upright(self) -> Rotation:
        """The tool's orientation for this pass: upright, at the pass's yaw (T2B)."""
        return _upright_at(self._pass_yaw_rad(), *self.tcp_turn_rad)

    def _untilted(self) -> Rotation:
        """Upright at the pass's yaw without FEEL's turn (T2B)."""
        return _untilted_at(self._pass_yaw_rad())

    def _pass_yaw_rad(self) -> float:
        """The tool's yaw for this pass: the nominal opening's and the pass's offset (rad, B)."""
        return self.hole.yaw_rad + self.search_pass.yaw_offset_rad

    def rock_angle_rad(self, obs: Observation, axis: int = 0) -> float:
        """The TCP's turn about T x from upright at the pass's yaw (``axis`` 0, rad), or about
        T y from there turned by the commanded turn about T x (``axis`` 1)."""
        reference = self._untilted()
        if axis == 1:
            reference = reference * Rotation.from_euler("x", self.tcp_turn_rad[0])
        relative = reference.inv() * rotation_from_rpy(obs.arm.tcp.rpy_rad)
        return float(relative.as_rotvec()[axis])

    @property
    def at_feel_site(self) -> bool:
        """The tip goes to FEEL's site (``rock.site_m``) instead of the pattern: FEEL is due at
        this pass's touch and has not begun, or is running."""
        rock = self.rock
        if rock is None or rock.site_m <= 0.0:
            return False
        if self._phase is Phase.FEEL:
            return True
        return not self.felt and self.memory.pass_index >= rock.at_pass

    def tip_target(self, s_m: float, height_m: float) -> np.ndarray:
        """The tip's target in B (m) at path length ``s_m`` of the pattern (turned by the
        present pass's ``pattern_turn_rad``; in a retrace, ``near_miss.outward_m`` further from its
        centre, or nearer with ``retrace_inward``), ``height_m`` above the nominal board; at
        FEEL's site (``at_feel_site``) ``rock.site_m`` from the nominal opening along its y
        instead."""
        u, v = self._pattern.offset(s_m)
        radius = math.hypot(u, v)
        detector, run = self.near_misses, self.memory
        if detector is not None and run.retrace_until_m is not None and radius > 0.0:
            step = detector.settings.outward_m * (-1.0 if run.retrace_inward else 1.0)
            scale = max(0.0, 1.0 + step / radius)  # a retrace's ring
            u, v = u * scale, v * scale
        turn = self.hole.yaw_rad + self.search_pass.pattern_turn_rad
        if self.at_feel_site:
            assert self.rock is not None
            u, v, turn = 0.0, self.rock.site_m, self.hole.yaw_rad
        planar = Rotation.from_euler("z", turn).apply([u, v, 0.0])
        return np.array([self.hole.x_m, self.hole.y_m, self.hole.z_m + height_m]) + planar

    def board_tcp_z_m(self) -> float:
        """The TCP's height (B, m) that puts the tip on the nominal board at the pattern's
        present point, the plug upright at the pass's yaw."""
        return float(self._tcp_target(self.tip_target(self.memory.s_m, 0.0))[2])

    def tip_t(self) -> np.ndarray:
        """The plug's tip in T (m): ``face_offset_m`` along T x, then ``length_m`` along the
        plug's axis, T z turned back by ``grasp_turn_rad`` (about T x, then T y: the axis
        that the TCP's turn by it sets upright), T z for the nominal grasp. Every place the
        machine puts or reads the tip takes it from here."""
        offset_t = np.array([self.face_offset_m or 0.0, 0.0, 0.0])
        return offset_t + self.plug.length_m * _plug_axis_t(*self.grasp_turn_rad)

    def tip_b(self, obs: Observation) -> np.ndarray:
        """The plug's tip in B (m) with the TCP at ``obs``'s pose."""
        rotation = rotation_from_rpy(obs.arm.tcp.rpy_rad)
        return np.asarray(obs.arm.tcp.xyz_m, dtype=float) + rotation.apply(self.tip_t())

    def _tcp_target(self, tip: np.ndarray) -> np.ndarray:
        """The TCP's place (B, m) that puts the tip at ``tip``, the TCP at the pass's
        orientation (``_upright``) and the tip where ``tip_t`` has it."""
        return tip - self._upright().apply(self.tip_t())

    def reach(self, obs: Observation, tip: np.ndarray) -> bool:
        """The TCP is within ``pose_tol_m`` of where it puts the tip at ``tip`` (B, m)."""
        error = self._tcp_target(tip) - np.asarray(obs.arm.tcp.xyz_m)
        return bool(np.linalg.norm(error) <= self.config.pose_tol_m)

    def reach_xy(self, obs: Observation, tip: np.ndarray) -> bool:
        """As ``reach``, in x and y only (the press sets z)."""
        error = self._tcp_target(tip)[:2] - np.asarray(obs.arm.tcp.xyz_m[:2])
        return bool(np.linalg.norm(error) <= self.config.pose_tol_m)

    def turned(self, obs: Observation) -> bool:
        """The TCP is within ``turn_tol_rad`` of this pass's orientation."""
        turn = rotation_error(rotation_from_rpy(obs.arm.tcp.rpy_rad), self._upright())
        return bool(np.linalg.norm(turn) <= self.config.turn_tol_rad)

    def servo(self, obs: Observation, tip: np.ndarray) -> Command:
        """Toward the TCP pose that puts the tip at ``tip`` (B, m)."""
        cfg = self.config
        error = self._tcp_target(tip) - np.asarray(obs.arm.tcp.xyz_m)
        return self._command(obs, cfg.pose_gain_1_s * error)

    def pressed(self, obs: Observation, force: float, moving: bool = False) -> Command:
        """x, y on the pattern at the swept length (its velocity ahead when ``moving``), z by
        the admittance on the press (``force``: the tared force, N)."""
        cfg = self.config
        now = self._tcp_target(self.tip_target(self.memory.s_m, 0.0))
        v = cfg.pose_gain_1_s * (now - np.asarray(obs.arm.tcp.xyz_m))
        if moving:
            ahead = self._tcp_target(
                self.tip_target(self.memory.s_m + cfg.sweep_speed_m_s * LEAD_S, 0.0)
            )
            v += (ahead - now) / LEAD_S
        v[2] = cfg.force_gain_m_s_n * (force - cfg.press_force_n)
        return self._command(obs, v)

    def descend(
        self, obs: Observation, speed_m_s: float, hold_xy: np.ndarray | None = None
    ) -> Command:
        """Down at ``speed_m_s`` (up when negative), x, y held on the pattern's point (or at
        ``hold_xy``, B, m)."""
        cfg = self.config
        if hold_xy is not None:
            xy = hold_xy
        else:
            xy = self._tcp_target(self.tip_target(self.memory.s_m, 0.0))[:2]
        v = np.zeros(3)
        v[:2] = cfg.pose_gain_1_s * (xy - np.asarray(obs.arm.tcp.xyz_m[:2]))
        v[2] = -speed_m_s
        return self._command(obs, v)

    def tip_xy(self, obs: Observation) -> np.ndarray:
        """The plug's tip's x, y in B (m) (``tip_b``)."""
        return self.tip_b(obs)[:2]

    def servoed_push(
        self, obs: Observation, speed_m_s: float, tip_xy: np.ndarray, torque_t: np.ndarray
    ) -> Command:
        """The tip down at ``speed_m_s`` and held at ``tip_xy`` (B, m) while the TCP turns
        about it as the torque servo says for ``torque_t`` (N*m, in T)."""
        assert self.torque_servo is not None
        cfg = self.config
        rotation = rotation_from_rpy(obs.arm.tcp.rpy_rad)
        p_tcp = np.asarray(obs.arm.tcp.xyz_m, dtype=float)
        p_tip = self.tip_b(obs)
        v_tip = np.zeros(3)
        v_tip[:2] = cfg.pose_gain_1_s * (tip_xy - p_tip[:2])
        v_tip[2] = -speed_m_s
        w = self.torque_servo.rate_b(torque_t, rotation, self._upright())
        v, w = pivot_twist(p_tcp, p_tip, clamp_norm(v_tip, cfg.move_speed_m_s), w)
        return Command(twist=bounded_twist(v, w, cfg.move_speed_m_s, cfg.rotate_speed_rad_s))

    def _command(self, obs: Observation, v: np.ndarray) -> Command:
        cfg = self.config
        v = clamp_norm(v, cfg.move_speed_m_s)
        turn = rotation_error(rotation_from_rpy(obs.arm.tcp.rpy_rad), self._upright())
        w = clamp_norm(cfg.pose_gain_1_s * turn, cfg.rotate_speed_rad_s)
        return Command(twist=bounded_twist(v, w, cfg.move_speed_m_s, cfg.rotate_speed_rad_s))
