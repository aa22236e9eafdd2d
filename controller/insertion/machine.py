"""The insertion state machine: ``step(observation) -> Command``, pure and non-blocking.

The phases, their rules and the transition table are documented in docs/ARCHITECTURE.md
("Insertion state machine"); the table itself is data (``definition.py``), checked when the
machine is built, and every transition the machine takes must be in it. Each tick, in this
order: a device fault ends the run; the e-stop button latches ESTOP; an operator in control
takes over (TELEOP); the timeouts, the hard limits and the slip policy are checked; then the
current phase's handler computes the command and may move on.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial.transform import Rotation

from controller.insertion.definition import (
    AUTONOMOUS,
    IN_CONTACT,
    INSERTION,
    TERMINAL,
    Definition,
    check_definition,
)
from controller.insertion.interface import (
    Command,
    FailureReason,
    GripperTarget,
    Observation,
    Phase,
    TeleopInput,
    Transition,
)
from controller.insertion.machine_config import MachineConfig
from controller.insertion.motion import (
    approach_rotation,
    bounded_twist,
    pivot_twist,
    rotation_error,
    tip_position,
)
from controller.insertion.search import HoleDetector, SearchPattern, lateral_resistance
from controller.insertion.signals import TactileSignals
from core.devices import Twist
from core.spatial import (
    clamp_norm,
    rotation_from_rpy,
    tilt_of_rotation,
    tilt_of_tool_axis,
    tool_z_in_base,
)
from core.task_geometry import HolePose, PlugGeometry

_HOLDING = (Phase.APPROACH, *IN_CONTACT)
_PROGRESS_M = 1e-4  # INSERT's push: the TCP this much lower is progress
_MAX_DT_S = 0.1  # a longer gap between ticks advances the search path by this much only
_TIMEOUT_KEYS = {
    Phase.GRASP: "grasp_s",
    Phase.APPROACH: "approach_s",
    Phase.SEARCH: "search_s",
    Phase.ALIGN: "align_s",
    Phase.INSERT: "insert_s",
    Phase.BACKOFF: "backoff_s",
    Phase.RELEASE: "release_s",
    Phase.RETRACT: "retract_s",
}


@dataclass
class _Stage:
    """What the current phase has done so far (reset on every phase entry)."""

    entered_t_s: float
    name: str = ""
    since_t_s: float = 0.0  # when ``name`` began, or a condition started to hold
    count: int = 0  # successive new estimates satisfying the phase's rule (SEARCH: no contact)
    z0_m: float = 0.0  # the TCP's height on entry
    detector: HoleDetector | None = None  # SEARCH: the hole-found rule
    v_tip: np.ndarray = field(default_factory=lambda: np.zeros(3))  # SEARCH: last command;
    # ALIGN: the horizontal unit vector against the lean
    resistance0: float = math.nan  # ALIGN: the lateral resistance when it began (noise units)
    rise: float = 0.0  # ALIGN: the lateral resistance's rise since (noise units)
    lowest: float = math.inf  # INSERT: lowest tilt torque so far
    point: np.ndarray = field(default_factory=lambda: np.zeros(3))  # ALIGN: the heel at its start
    frame_t_s: float = math.nan  # GRASP: time of the last tactile estimate counted
    stall_z_m: float = math.nan  # INSERT: the TCP's height when the press load was reached
    yaw_sign: float = 1.0  # INSERT: the yaw sweep's present direction
    reversals: int = 0  # INSERT: the yaw sweep's turns so far
    start_yaw_rad: float = 0.0  # INSERT: the yaw (from the nominal) when the sweep began

    @classmethod
    def entered(cls, obs: Observation) -> _Stage:
        """The stage of a phase entered at ``obs``."""
        return cls(entered_t_s=obs.t_s, since_t_s=obs.t_s, z0_m=float(obs.arm.tcp.xyz_m[2]))


class InsertionMachine:
    """The insertion machine for one run (implements ``interface.Machine``).

    ``config``: the task's ``machine:`` section; ``plug``: the grasped plug; ``hole``: the
    opening's nominal pose in B. ``definition``: the transition table (the insertion table by
    default; checked here, DefinitionError if malformed).
    """

    def __init__(
        self,
        config: MachineConfig,
        plug: PlugGeometry,
        hole: HolePose,
        definition: Definition = INSERTION,
    ) -> None:
        check_definition(definition)
        self.config = config
        self.plug = plug
        self.hole = hole
        self.definition = definition
        self.signals = TactileSignals(config.signals)
        self._pattern = SearchPattern(
            config.search.pattern, config.search.pitch_m, config.search.uncertainty_xy_m
        )
        self._hole_xyz = np.array([hole.x_m, hole.y_m, hole.z_m])
        self._hole_yaw = Rotation.from_euler("z", hole.yaw_rad)
        self._approach_rot = approach_rotation(
            hole.yaw_rad, config.approach.tilt_rad, config.approach.tilt_axis
        )
        self._phase = definition.initial
        self._transitions: list[Transition] = []
        self._stage_or_none: _Stage | None = None  # None until the first step
        self._last_t_s: float | None = None
        self._tick_s = 0.0
        self._autonomous_s = 0.0
        self._retries = 0
        self._regrasp = False
        self._keep_grasp = False  # GRASP re-zeroes on the plug held (a resume): no capture
        self._released = False
        self._preload = config.approach.contact_sigma  # SEARCH's axial load (noise units)
        self._search_s_m = 0.0  # SEARCH's path length so far (kept when searching again)
        self._yaw_passes_from_m: float | None = None  # that length at SEARCH's first timeout
        self._search_again = False  # BACKOFF: a press that never engaged ends in APPROACH
        self._surface_z: float | None = None  # the board surface's height found by touch (m)
        self._last_jam_z: float | None = None  # the lowest edge's height at the last jam (m)
        self._rim_z: float | None = None  # ... at a jam no deeper than the one before it (m)
        self._rule = ""  # the rule deciding this tick's command (Command.rule)

    # -- the Machine protocol ------------------------------------------------------------

    @property
    def phase(self) -> Phase:
        return self._phase

    @property
    def transitions(self) -> tuple[Transition, ...]:
        return tuple(self._transitions)

    @property
    def retries(self) -> int:
        """Back-offs and re-grasps so far."""
        return self._retries

    def step(self, observation: Observation) -> Command:
        """One tick: the command for ``observation`` (see the module doc for the order),
        naming the rule that decided it (``Command.rule``)."""
        self._rule = ""
        command = self._decide(observation)
        return dataclasses.replace(command, rule=self._rule)

    def _decide(self, obs: Observation) -> Command:
        dt = 0.0 if self._last_t_s is None else max(obs.t_s - self._last_t_s, 0.0)
        self._last_t_s = obs.t_s
        self._tick_s = dt
        if self._stage_or_none is None:
            self._stage_or_none = _Stage.entered(obs)
        if self._phase in AUTONOMOUS:
            self._autonomous_s += dt
        new = self.signals.update(obs.wrench)
        if self._phase in TERMINAL:
            self._fire("hold")
            return _hold()
        if has_fault(obs):
            return self._fail(obs, FailureReason.DEVICE_FAULT)
        if obs.teleop.estop and self._phase is not Phase.ESTOP:
            self._go(obs, Phase.ESTOP, "estop")
        if self._phase is Phase.ESTOP:
            return self._estop(obs)
        if obs.teleop.in_control and self._phase in AUTONOMOUS:
            self._go(obs, Phase.TELEOP, "operator_takeover")
        if self._phase is Phase.TELEOP:
            return self._teleop(obs)
        failure = self._checks(obs)
        if failure is not None:
            return failure
        if self._phase in _HOLDING and self._slipped(obs, new):
            return self._on_slip(obs)
        return self._handlers[self._phase](self, obs, new)

    @property
    def _stage(self) -> _Stage:
        """What the current phase has done so far (RuntimeError before the first step)."""
        if self._stage_or_none is None:
            raise RuntimeError("the insertion machine has no phase stage before its first step")
        return self._stage_or_none

    # -- transitions -----------------------------------------------------------------------

    def _fire(self, rule: str) -> None:
        """Name the rule deciding this tick's command: ``phase.rule``."""
        self._rule = f"{self._phase.value}.{rule}"

    def _go(self, obs: Observation, target: Phase, guard: str, rule: str = "") -> None:
        """Move to ``target`` under ``guard`` (``rule``: which of the guard's rules fired)."""
        if not self.definition.allows(self._phase, target, guard):
            raise RuntimeError(
                f"transition {self._phase.name} -> {target.name} ({guard}) "
                "is not in the machine's definition"
            )
        self._transitions.append(Transition(obs.t_s, self._phase, target, guard, rule))
        self._fire(f"{guard}:{rule}" if rule else guard)
        self._phase = target
        self._stage_or_none = _Stage.entered(obs)
        if guard == "hole_found":  # a new catch: no jam there yet
            self._last_jam_z = self._rim_z = None
        if target is Phase.RELEASE:
            self._released = True

    def _fail(self, obs: Observation, reason: FailureReason) -> Command:
        self._go(obs, Phase.FAILED, reason.value)
        return _hold()

    def _resume_phase(self, obs: Observation) -> Phase:
        """Where autonomy resumes after TELEOP or ESTOP, from the contact state: after the
        plug was released, RETRACT; no grasp or no tactile baseline, GRASP; grasped without
        contact, APPROACH; in contact with the tip in the opening, ALIGN; otherwise SEARCH."""
        if self._released:
            return Phase.RETRACT
        if not obs.gripper.holding or not self.signals.ready:
            return Phase.GRASP
        if self.signals.magnitude < self.config.approach.contact_sigma:
            return Phase.APPROACH
        tip_z = tip_position(obs.arm.tcp, self.plug.length_m)[2]
        if tip_z < self.hole.z_m - self.config.search.in_hole_depth_m:
            return Phase.ALIGN
        return Phase.SEARCH

    def _resume(self, obs: Observation, target: Phase, guard: str) -> None:
        """Go to ``target``; into GRASP with the plug held, keeping the grasp: settle and
        re-zero, without capturing the open gel again (a gel pressed on the plug is no open
        reference, and opening the fingers could drop the plug from where the operator left
        it)."""
        if target is Phase.GRASP and obs.gripper.holding:
            self._keep_grasp = True
        self._go(obs, target, guard)

    # -- checks common to the autonomous phases ------------------------------------------

    def _checks(self, obs: Observation) -> Command | None:
        """FAILED for a timeout or an exceeded hard limit, else None."""
        timeouts = self.config.timeouts
        in_phase = obs.t_s - self._stage.entered_t_s
        if self._autonomous_s > timeouts.total_s:
            return self._fail(obs, FailureReason.TIMEOUT)
        if in_phase > getattr(timeouts, _TIMEOUT_KEYS[self._phase]):
            if self._phase is Phase.ALIGN:  # a plug that would not align: lift, catch again
                return self._back_off(obs, "align_timeout")
            if self._phase is Phase.SEARCH:  # no catch: search again, at other yaws
                if self._yaw_passes_from_m is None:
                    self._yaw_passes_from_m = self._search_s_m
                return self._back_off(obs, "search_timeout")
            return self._fail(obs, FailureReason.TIMEOUT)
        if self._phase in _HOLDING and self._limit_exceeded(obs):
            return self._fail(obs, FailureReason.LIMIT_EXCEEDED)
        return None

    def _limit_exceeded(self, obs: Observation) -> bool:
        limits = self.config.limits
        rotation = rotation_from_rpy(obs.arm.tcp.rpy_rad)
        if tilt_of_rotation(rotation) > limits.max_tilt_rad:
            return True
        if self._phase is Phase.APPROACH:
            overtravel = self.hole.z_m - self.config.approach.overtravel_m
            if tip_position(obs.arm.tcp, self.plug.length_m)[2] < overtravel:
                return True
        if not self.signals.ready:
            return False
        deviation = np.abs(self.signals.deviation)
        return bool(
            max(deviation[0], deviation[1]) > limits.tilt_torque_limit
            or deviation[2] > limits.inplane_torque_limit
            or self.signals.axial_force > limits.force_limit
        )

    def _slipped(self, obs: Observation, new: bool) -> bool:
        if not obs.gripper.holding:
            return True
        wrench = obs.wrench
        if not new or wrench is None:
            return False
        if self.config.slip.trigger == "suspected":
            return wrench.slip_suspected or wrench.slip_gross
        return wrench.slip_gross

    def _on_slip(self, obs: Observation) -> Command:
        if self.config.slip.policy == "fail":
            return self._fail(obs, FailureReason.SLIP)
        if self._retries >= self.config.backoff.max_retries:
            return self._fail(obs, FailureReason.TOO_MANY_RETRIES)
        self._retries += 1
        self._regrasp = True
        self._go(obs, Phase.GRASP, "slip_regrasp")
        return _hold()

    # -- overrides -------------------------------------------------------------------------

    def _estop(self, obs: Observation) -> Command:
        teleop = obs.teleop
        if not teleop.estop and teleop.estop_ack:
            target = Phase.TELEOP if teleop.in_control else self._resume_phase(obs)
            self._resume(obs, target, "estop_acknowledged")
        else:
            self._fire("hold")
        return _hold()

    def _teleop(self, obs: Observation) -> Command:
        teleop = obs.teleop
        if teleop.hand_back:
            self._resume(obs, self._resume_phase(obs), "hand_back")
            return _hold()
        self._fire("operator")
        return operator_command(teleop, self.config)

    # -- phases ----------------------------------------------------------------------------

    def _grasp(self, obs: Observation, new: bool) -> Command:
        """Lift (after a slip), open a little (re-grasp), capture the open gel while the
        fingers travel fast to just above the plug's thickness, close, settle, re-zero,
        baseline; resumed with the plug held (``_resume``): settle, re-zero, baseline."""
        stage, settings = self._stage, self.config.gripper
        first = "lift" if self._regrasp else ("settle" if self._keep_grasp else "capture")
        self._fire(stage.name or first)
        if stage.name == "":
            stage.name, self._keep_grasp = first, False
            stage.since_t_s = obs.t_s
            if stage.name == "capture":
                return self._capture_open(obs)
        if stage.name == "lift":
            if obs.arm.tcp.xyz_m[2] >= stage.z0_m + self.config.slip.lift_m:
                self._next_stage(obs, "open")
                return Command(
                    twist=Twist(),
                    gripper=self._open_target(obs.gripper.width_m + settings.regrasp_gap_m),
                )
            return self._tcp_twist(np.array([0.0, 0.0, self.config.approach.move_speed_m_s]))
        if stage.name == "open":
            if obs.t_s - stage.since_t_s >= settings.settle_s and not obs.gripper.moving:
                self._regrasp = False
                self._next_stage(obs, "capture")
                return self._capture_open(obs)
            return _hold()
        if stage.name == "capture":
            # the open gel: the estimator takes the next zeroing_frames frames; wait for one
            # more, and for the fingers' fast travel to end
            if obs.wrench is not None and obs.wrench.t_s != stage.frame_t_s:
                stage.frame_t_s = obs.wrench.t_s
                stage.count += 1
            if stage.count > self.config.signals.zeroing_frames and not obs.gripper.moving:
                self._next_stage(obs, "close")
            return _hold()
        if stage.name == "close":
            self._next_stage(obs, "settle")
            return Command(twist=Twist(), gripper=self._close_target())
        if stage.name == "settle":
            if not (obs.gripper.holding and not obs.gripper.moving):
                stage.since_t_s = obs.t_s
            elif obs.t_s - stage.since_t_s >= settings.settle_s:
                self._next_stage(obs, "zero")
                self.signals.reset()
                return Command(twist=Twist(), rezero_tactile=True)
            return _hold()
        # "zero": wait for the estimator's zeroing, then for the baseline
        if self.signals.ready:
            self._go(obs, Phase.APPROACH, "grasped_and_zeroed")
        return _hold()

    def _approach(self, obs: Observation, new: bool) -> Command:
        """Servo to the tilted pose above the opening (rising first if the tip is below its
        height there, so the plug never sweeps over the board), then descend until contact."""
        stage, settings = self._stage, self.config.approach
        rotation = rotation_from_rpy(obs.arm.tcp.rpy_rad)
        resume = self._planar(self._pattern.offset(self._search_s_m))
        target_tip = self._hole_xyz + resume + np.array([0.0, 0.0, settings.height_m])
        if stage.name == "":
            target_rot = self._search_rotation()
            target_tcp = target_tip - target_rot.apply([0.0, 0.0, self.plug.length_m])
            error = target_tcp - np.asarray(obs.arm.tcp.xyz_m)
            turn = rotation_error(rotation, target_rot)
            tip_z = tip_position(obs.arm.tcp, self.plug.length_m)[2]
            if tip_z < target_tip[2] - settings.pose_tol_m:
                # the tip straight up to its height first, not turning (it may be in the
                # opening)
                error = np.array([0.0, 0.0, target_tip[2] - tip_z + settings.pose_tol_m])
                turn = np.zeros(3)
            if np.linalg.norm(error) <= settings.pose_tol_m and (
                np.linalg.norm(turn) <= settings.angle_tol_rad
            ):
                self._next_stage(obs, "descend")
            else:
                self._fire("pose_servo")
                v = clamp_norm(settings.pose_gain_1_s * error, settings.move_speed_m_s)
                w = clamp_norm(settings.pose_gain_1_s * turn, settings.rotate_speed_rad_s)
                return self._command(v, w)
        if new:
            contact = self.signals.magnitude >= settings.contact_sigma
            stage.count = stage.count + 1 if contact else 0
        if stage.count >= settings.contact_frames:
            rotation = rotation_from_rpy(obs.arm.tcp.rpy_rad)
            self._surface_z = float(self._lowest_edge(obs, rotation)[2])
            self._go(obs, Phase.SEARCH, "surface_contact")
            return _hold()
        self._fire("descend")
        v_tip = np.array([0.0, 0.0, -settings.descend_speed_m_s])
        return self._tip_command(obs, v_tip, self._hold_rotation(rotation))

    def _search(self, obs: Observation, new: bool) -> Command:
        """Drag the tip along the pattern with a preload; watch the drag resistance."""
        stage, settings = self._stage, self.config.search
        if stage.detector is None:
            stage.detector = HoleDetector(settings, self.config.signals.ema_alpha)
        self._search_s_m += settings.speed_m_s * min(self._tick_s, _MAX_DT_S)
        offset = self._planar(self._pattern.offset(self._search_s_m))
        ahead = self._planar(self._pattern.offset(self._search_s_m + 1e-4)) - offset
        tangent = ahead / np.linalg.norm(ahead) if np.linalg.norm(ahead) > 0 else ahead
        tip = tip_position(obs.arm.tcp, self.plug.length_m)
        gain = self.config.approach.pose_gain_1_s
        rotation = rotation_from_rpy(obs.arm.tcp.rpy_rad)
        if stage.name == "probe":
            return self._probe(obs, new)
        if new:
            stage.count = (
                stage.count + 1 if (self.signals.magnitude < settings.contact_lost_sigma) else 0
            )
            if stage.count >= settings.contact_lost_frames:
                self._next_stage(obs, "probe")
                return _hold()
            elapsed = obs.t_s - stage.entered_t_s
            fired = stage.detector.update(self.signals, rotation, stage.v_tip, elapsed)
            if fired:
                if stage.detector.load_reference is not None:
                    self._preload = max(stage.detector.load_reference, 1.0)
                self._go(obs, Phase.ALIGN, "hole_found", fired)
                return _hold()
        self._fire("drag")
        v_tip = np.zeros(3)
        v_tip[:2] = settings.speed_m_s * tangent[:2] + gain * (
            self._hole_xyz[:2] + offset[:2] - tip[:2]
        )
        v_tip[:2] = clamp_norm(v_tip[:2], 2.0 * settings.speed_m_s)
        v_tip[2] = gain * (stage.z0_m - settings.press_depth_m - obs.arm.tcp.xyz_m[2])
        stage.v_tip = clamp_norm(v_tip, self.config.approach.move_speed_m_s)
        return self._tip_command(obs, stage.v_tip, self._hold_rotation(rotation))

    def _probe(self, obs: Observation, new: bool) -> Command:
        """SEARCH after losing contact: the tip straight down until contact again (in the
        opening: ALIGN; on the surface: drag on) or past the overtravel (contact lost)."""
        stage, approach = self._stage, self.config.approach
        tip_z = tip_position(obs.arm.tcp, self.plug.length_m)[2]
        if new:
            contact = self.signals.magnitude >= approach.contact_sigma
            stage.count = stage.count + 1 if contact else 0
        if stage.count >= approach.contact_frames:
            if tip_z <= self.hole.z_m - self.config.search.in_hole_depth_m:
                self._go(obs, Phase.ALIGN, "hole_found", "probe")
            else:
                self._fire("probe_surface")
                self._next_stage(obs, "")
                stage.z0_m = float(obs.arm.tcp.xyz_m[2])
            return _hold()
        if tip_z < self.hole.z_m - approach.overtravel_m:
            return self._fail(obs, FailureReason.CONTACT_LOST)
        self._fire("probe")
        rotation = rotation_from_rpy(obs.arm.tcp.rpy_rad)
        v_tip = np.array([0.0, 0.0, -approach.descend_speed_m_s])
        return self._tip_command(obs, v_tip, self._hold_rotation(rotation))

    def _align(self, obs: Observation, new: bool) -> Command:
        """Seek the wall with the heel, turn upright about it, then null the torques (see
        config.AlignSettings)."""
        stage, settings = self._stage, self.config.align
        rotation = rotation_from_rpy(obs.arm.tcp.rpy_rad)
        if stage.name == "" and tilt_of_rotation(rotation) <= settings.tilt_tol_rad:
            # upright already (after a jam's back-off): no heel to seek or turn about
            self._after_upright(obs, rotation)
            stage.start_yaw_rad = _yaw_of(rotation) - self.hole.yaw_rad
        if stage.name == "":
            self._next_stage(obs, "seek")
            lean = rotation.apply([0.0, 0.0, 1.0])
            lean[2] = 0.0
            norm = float(np.linalg.norm(lean))
            stage.v_tip = -lean / norm if norm > 1e-9 else np.zeros(3)
            stage.point = self._lowest_edge(obs, rotation)
        if stage.name == "servo":
            return self._align_servo(obs, new)
        if stage.name == "width":
            return self._align_width(obs, rotation, new)
        if stage.name == "yaw":
            return self._align_yaw(obs, rotation, new)
        if new and np.linalg.norm(stage.v_tip) > 0.0:
            resistance = lateral_resistance(self.signals, rotation, stage.v_tip)[1]
            if math.isnan(stage.resistance0):
                stage.resistance0 = resistance
            stage.rise = resistance - stage.resistance0
            held = stage.rise >= settings.wall_sigma
            stage.count = stage.count + 1 if held else 0
        if stage.name == "seek":
            return self._align_seek(obs, rotation)
        return self._align_turn(obs, rotation)

    def _align_seek(self, obs: Observation, rotation: Rotation) -> Command:
        """ALIGN's seek stage: the heel against the lean until the wall holds it."""
        stage, settings = self._stage, self.config.align
        edge = self._lowest_edge(obs, rotation)
        moved = float(np.linalg.norm((edge - stage.point)[:2]))
        if stage.count >= settings.frames or not np.any(stage.v_tip):
            self._fire("wall")
            self._next_stage(obs, "turn")
            stage.point = edge
            return _hold()
        if moved >= settings.seek_max_m:
            return self._back_off(obs, "no_wall")
        self._fire("seek")
        v_edge = settings.seek_speed_m_s * stage.v_tip
        v_edge[2] = -self._press_rate()
        v_tcp, w = pivot_twist(
            np.asarray(obs.arm.tcp.xyz_m, dtype=float), edge, v_edge, self._heel_yaw_rate(rotation)
        )
        return self._command(v_tcp, w)

    def _align_turn(self, obs: Observation, rotation: Rotation) -> Command:
        """ALIGN's turn stage: upright about the heel, the heel held against the wall."""
        stage, settings = self._stage, self.config.align
        angle, axis = tilt_of_tool_axis(tool_z_in_base(rotation))
        if angle <= settings.tilt_tol_rad:
            self._fire("upright")
            self._after_upright(obs, rotation)
            stage.start_yaw_rad = _yaw_of(rotation) - self.hole.yaw_rad
            return _hold()
        self._fire("turn")
        edge = self._lowest_edge(obs, rotation)
        hold = float(np.clip(1.0 - stage.rise / settings.wall_sigma, -1.0, 1.0))
        v_edge = settings.seek_speed_m_s * hold * stage.v_tip
        v_edge[2] = self.config.approach.pose_gain_1_s * (stage.point[2] - edge[2])
        w = clamp_norm(
            settings.upright_gain_1_s * angle * axis + self._heel_yaw_rate(rotation),
            settings.max_angular_speed_rad_s,
        )
        v_tcp, w = pivot_twist(np.asarray(obs.arm.tcp.xyz_m, dtype=float), edge, v_edge, w)
        return self._command(v_tcp, w)

    def _after_upright(self, obs: Observation, rotation: Rotation) -> None:
        """The stage after the turn: the servo if the plug is in the opening, else the width
        stage (toward the low end the in-plane torque names), or the yaw stage when the
        in-plane torque names no side (below ``align.width_sigma``) or the stage is off."""
        stage = self._stage
        if self._entered(obs, rotation):
            self._next_stage(obs, "servo")
        elif self.config.align.width_speed_m_s > 0.0 and (
            abs(float(self.signals.normalised[2])) >= self.config.align.width_sigma
        ):
            self._next_stage(obs, "width")
            toward = -math.copysign(1.0, float(self.signals.normalised[2]))
            along = rotation.apply([toward, 0.0, 0.0])
            along[2] = 0.0
            stage.v_tip = along / np.linalg.norm(along)
            stage.point = tip_position(obs.arm.tcp, self.plug.length_m)
            stage.resistance0 = math.nan
        else:
            self._next_stage(obs, "yaw")

    def _align_width(self, obs: Observation, rotation: Rotation, new: bool) -> Command:
        """ALIGN's width stage (see config.AlignSettings): slide toward the low end, pressing,
        until the plug enters; the end wall or ``width_max_m`` first: the yaw stage."""
        stage, settings = self._stage, self.config.align
        if self._entered(obs, rotation):
            self._fire("entered")
            self._next_stage(obs, "servo")
            return _hold()
        if new:
            resistance = lateral_resistance(self.signals, rotation, stage.v_tip)[1]
            if math.isnan(stage.resistance0):
                stage.resistance0 = resistance
            held = resistance - stage.resistance0 >= settings.wall_sigma
            stage.count = stage.count + 1 if held else 0
        tip = tip_position(obs.arm.tcp, self.plug.length_m)
        slid = float(np.linalg.norm((tip - stage.point)[:2]))
        if stage.count >= settings.frames or slid >= settings.width_max_m:
            self._fire("end_wall" if stage.count >= settings.frames else "width_done")
            self._next_stage(obs, "yaw")
            return _hold()
        self._fire("width_slide")
        v_tip = settings.width_speed_m_s * stage.v_tip
        v_tip[2] = -self._press_rate()
        return self._tip_command(obs, v_tip, self._heel_yaw_rate(rotation))

    def _heel_yaw_rate(self, rotation: Rotation) -> np.ndarray:
        """Angular velocity in B yielding in yaw (about T z) to the torque about the plug's
        axis while the heel is caught (``align.heel_yaw_gain``)."""
        about_t_z = float(self.signals.torque_t[2])
        return rotation.apply([0.0, 0.0, -self.config.align.heel_yaw_gain * about_t_z])

    def _align_yaw(self, obs: Observation, rotation: Rotation, new: bool) -> Command:
        """ALIGN's yaw stage (upright but not in the opening): sweep the yaw about the tip
        axis, a triangle wave within +-``insert.yaw_sweep_rad`` of the opening's nominal yaw,
        pressing with SEARCH's load, until the plug enters (then the servo stage); back
        where the sweep began after ``insert.sweeps`` whole sweeps: not over the opening
        (BACKOFF, then SEARCH again)."""
        stage, settings = self._stage, self.config.insert
        if self._entered(obs, rotation):
            self._fire("entered")
            self._next_stage(obs, "servo")
            return _hold()
        if new and self.config.align.twist_sigma > 0.0:
            twisted = abs(float(self.signals.torque_t[2])) >= self.config.align.twist_sigma
            stage.count = stage.count + 1 if twisted else 0
            if stage.count >= self.config.align.frames:
                self._fire("twist_held")  # the long walls hold the yaw: in the slot
                self._next_stage(obs, "servo")
                return _hold()
        yaw = _yaw_of(rotation) - self.hole.yaw_rad
        if stage.yaw_sign * yaw >= settings.yaw_sweep_rad:
            stage.yaw_sign = -stage.yaw_sign
            stage.reversals += 1
        if stage.reversals >= 2 * settings.sweeps and (
            stage.yaw_sign * (yaw - stage.start_yaw_rad) >= 0.0
        ):
            if self._depth_in(obs, rotation) >= 0.5 * self.config.align.enter_m:
                self._fire("entering")  # on its way in as the sweep ends: the servo
                self._next_stage(obs, "servo")
                return _hold()
            return self._back_off(obs, "not_entered")
        self._fire("yaw_sweep")
        w = np.array([0.0, 0.0, stage.yaw_sign * settings.yaw_rate_rad_s])
        return self._tip_command(obs, np.array([0.0, 0.0, -self._press_rate()]), w)

    def _entered(self, obs: Observation, rotation: Rotation) -> bool:
        """True when the plug is in the opening: ``_depth_in`` at least ``align.enter_m``."""
        return self._depth_in(obs, rotation) >= self.config.align.enter_m

    def _depth_in(self, obs: Observation, rotation: Rotation) -> float:
        """How far the plug is into the opening, m: ``_depth``, or less, how far its lowest
        edge is below the rim it stood on at repeated jams (``_note_jam``)."""
        depth = self._depth(obs, rotation)
        if self._rim_z is None:
            return depth
        return min(depth, self._rim_z - float(self._lowest_edge(obs, rotation)[2]))

    def _note_jam(self, obs: Observation, rotation: Rotation) -> None:
        """A jam no deeper (by ``align.enter_m``) than the jam before it at this catch: the
        plug stands on the opening's rim, whatever the depth by touch says (that depth
        assumes the nominal grasp; an unknown in-grasp tilt moves the lowest edge by up to
        a millimetre). From then on the plug has entered only ``align.enter_m`` below where
        it stood, so ALIGN's width and yaw stages and INSERT's press run again."""
        edge_z = float(self._lowest_edge(obs, rotation)[2])
        last, self._last_jam_z = self._last_jam_z, edge_z
        if last is not None and edge_z > last - self.config.align.enter_m:
            self._rim_z = edge_z

    def _depth(self, obs: Observation, rotation: Rotation) -> float:
        """How far the tip face's lowest edge is below the board surface found by touch (the
        nominal opening's height before any touch), m."""
        surface = self.hole.z_m if self._surface_z is None else self._surface_z
        return surface - float(self._lowest_edge(obs, rotation)[2])

    def _align_servo(self, obs: Observation, new: bool) -> Command:
        """ALIGN's servo stage (the plug in the opening): yield to the torques about the tip,
        pressing with SEARCH's load; aligned once every torque is within tolerance under at
        least half that load, or once the plug is down to INSERT's depth."""
        stage, settings = self._stage, self.config.align
        if new:
            loaded = self.signals.axial_force_n >= 0.5 * self._preload
            aligned = loaded and self._torques_within_tolerance()
            stage.count = stage.count + 1 if aligned else 0
        rotation = rotation_from_rpy(obs.arm.tcp.rpy_rad)
        if self._depth(obs, rotation) >= self.config.insert.depth_m:
            stage.count = settings.frames  # slid in while turning: INSERT judges the depth
        if stage.count >= settings.frames:
            self._go(obs, Phase.INSERT, "aligned")
            return _hold()
        self._fire("within_tolerance" if self._torques_within_tolerance() else "torque_servo")
        w = clamp_norm(self._align_rate(rotation, 1.0), settings.max_angular_speed_rad_s)
        return self._tip_command(obs, np.array([0.0, 0.0, -self._press_rate()]), w)

    def _lowest_edge(self, obs: Observation, rotation: Rotation) -> np.ndarray:
        """The lowest of the four edge midpoints of the plug's tip face, in B: the edge a
        tilted plug leads with, and the one caught in the opening (ALIGN turns about it)."""
        tip = tip_position(obs.arm.tcp, self.plug.length_m)
        half_w, half_t = 0.5 * self.plug.width_m, 0.5 * self.plug.thickness_m
        offsets = rotation.apply(
            [[half_w, 0.0, 0.0], [-half_w, 0.0, 0.0], [0.0, half_t, 0.0], [0.0, -half_t, 0.0]]
        )
        return tip + offsets[int(np.argmin(offsets[:, 2]))]

    def _press_rate(self) -> float:
        """Downward tip speed keeping the axial load at SEARCH's preload: the descent speed
        times the load's shortfall relative to the preload, within +-1."""
        shortfall = (self._preload - self.signals.axial_force_n) / self._preload
        return self.config.approach.descend_speed_m_s * float(np.clip(shortfall, -1.0, 1.0))

    def _insert(self, obs: Observation, new: bool) -> Command:
        """Press with a bounded load, sweeping the yaw until the plug engages; then push
        straight down within the budgets; a jam backs off; the depth is success (see
        config.InsertSettings)."""
        stage, settings = self._stage, self.config.insert
        rotation = rotation_from_rpy(obs.arm.tcp.rpy_rad)
        if stage.name == "":
            self._next_stage(obs, "push" if self._entered(obs, rotation) else "press")
        target_load = settings.press_load_ratio * self._preload
        unloaded = self.signals.axial_force_n < target_load
        if self._depth(obs, rotation) >= settings.depth_m and unloaded:
            self._go(obs, Phase.RELEASE, "depth_reached")
            return _hold()
        if stage.name == "press":
            return self._press(obs, target_load)
        if new:
            torque = self.signals.torque_t
            tilt = float(math.hypot(torque[0], torque[1]))
            stage.lowest = min(stage.lowest, tilt)
            jammed = (
                tilt - stage.lowest >= settings.jam_rise_sigma
                or self.signals.axial_force > settings.force_budget
            )
            stage.count = stage.count + 1 if jammed else 0
        z_tcp = float(obs.arm.tcp.xyz_m[2])
        if math.isnan(stage.stall_z_m) or z_tcp < stage.stall_z_m - _PROGRESS_M:
            stage.stall_z_m, stage.since_t_s = z_tcp, obs.t_s
        stalled = obs.t_s - stage.since_t_s >= settings.stall_s
        if stage.count >= settings.jam_frames or stalled:
            self._note_jam(obs, rotation)
            return self._back_off(obs, "jam")
        self._fire("push")
        w = clamp_norm(
            self._align_rate(rotation, settings.compliance_scale),
            self.config.align.max_angular_speed_rad_s,
        )
        w[2] = 0.0  # the yaw found while pressing is held
        shortfall = (target_load - self.signals.axial_force_n) / target_load
        v_tip = np.array([0.0, 0.0, -settings.speed_m_s * float(np.clip(shortfall, -1.0, 1.0))])
        return self._tip_command(obs, v_tip, w)

    def _press(self, obs: Observation, target_load: float) -> Command:
        """INSERT's press stage: descend toward the press load; at the stall height sweep
        the yaw; engaged: the push stage; the sweeps done: back off and search again."""
        stage, settings = self._stage, self.config.insert
        z_tcp = float(obs.arm.tcp.xyz_m[2])
        rotation = rotation_from_rpy(obs.arm.tcp.rpy_rad)
        yaw = _yaw_of(rotation) - self.hole.yaw_rad
        if math.isnan(stage.stall_z_m) and not (self.signals.axial_force_n < 0.8 * target_load):
            stage.stall_z_m = z_tcp
            stage.start_yaw_rad = yaw
        reference = stage.z0_m if math.isnan(stage.stall_z_m) else stage.stall_z_m
        gave_way = not math.isnan(stage.stall_z_m) and (
            self.signals.axial_force_n < 0.5 * target_load
        )
        if z_tcp <= reference - settings.engage_m or gave_way:
            self._fire("engaged")
            self._next_stage(obs, "push")
            return _hold()
        w = np.zeros(3)
        if not math.isnan(stage.stall_z_m) and settings.yaw_sweep_rad > 0.0:
            if stage.yaw_sign * yaw >= settings.yaw_sweep_rad:
                stage.yaw_sign = -stage.yaw_sign
                stage.reversals += 1
            back_at_start = stage.reversals >= 2 * settings.sweeps and (
                stage.yaw_sign * (yaw - stage.start_yaw_rad) >= 0.0
            )
            if back_at_start:
                return self._back_off(obs, "not_engaged")
            w[2] = stage.yaw_sign * settings.yaw_rate_rad_s
        self._fire("press" if w[2] == 0.0 else "yaw_sweep")
        w[:2] = clamp_norm(
            self._align_rate(rotation, settings.compliance_scale),
            self.config.align.max_angular_speed_rad_s,
        )[:2]
        shortfall = (target_load - self.signals.axial_force_n) / target_load
        v_tip = np.array([0.0, 0.0, -settings.speed_m_s * float(np.clip(shortfall, -1.0, 1.0))])
        return self._tip_command(obs, v_tip, w)

    def _back_off(self, obs: Observation, guard: str) -> Command:
        """BACKOFF after a jam (then ALIGN) or a press that never engaged (then APPROACH and
        SEARCH again); FAILED when the retries are used up."""
        if self._retries >= self.config.backoff.max_retries:
            return self._fail(obs, FailureReason.TOO_MANY_RETRIES)
        self._retries += 1
        self._search_again = guard in (
            "not_engaged",
            "no_wall",
            "not_entered",
            "align_timeout",
            "search_timeout",
        )
        self._go(obs, Phase.BACKOFF, guard)
        return _hold()

    def _backoff(self, obs: Observation, new: bool) -> Command:
        """Lift the tip straight up by the back-off distance, then ALIGN again (after a jam)
        or APPROACH and SEARCH again (after a press that never engaged; then also until the
        tip's lowest edge is the back-off distance above the surface found)."""
        settings = self.config.backoff
        lifted = obs.arm.tcp.xyz_m[2] >= self._stage.z0_m + settings.distance_m
        if lifted and self._search_again:
            # SEARCH again from clear of the board: the tip's lowest edge above the surface
            rotation = rotation_from_rpy(obs.arm.tcp.rpy_rad)
            lifted = -self._depth(obs, rotation) >= settings.distance_m
        if lifted:
            if self._search_again:
                self._go(obs, Phase.APPROACH, "search_again")
            else:
                self._go(obs, Phase.ALIGN, "backed_off")
            return _hold()
        self._fire("lift")
        return self._tcp_twist(np.array([0.0, 0.0, settings.speed_m_s]))

    def _release(self, obs: Observation, new: bool) -> Command:
        """Open the gripper; wait until it has stopped."""
        stage = self._stage
        self._fire("open")
        if stage.name == "":
            self._next_stage(obs, "opening")
            return Command(
                twist=Twist(), gripper=self._open_target(self.config.gripper.open_width_m)
            )
        if obs.t_s - stage.since_t_s >= self.config.release.settle_s and not obs.gripper.moving:
            self._go(obs, Phase.RETRACT, "released")
        return _hold()

    def _retract(self, obs: Observation, new: bool) -> Command:
        """Lift the TCP straight up by the retract distance."""
        settings = self.config.release
        if obs.arm.tcp.xyz_m[2] >= self._stage.z0_m + settings.retract_distance_m:
            self._go(obs, Phase.DONE, "retracted")
            return _hold()
        self._fire("lift")
        return self._tcp_twist(np.array([0.0, 0.0, settings.retract_speed_m_s]))

    _handlers = {
        Phase.GRASP: _grasp,
        Phase.APPROACH: _approach,
        Phase.SEARCH: _search,
        Phase.ALIGN: _align,
        Phase.INSERT: _insert,
        Phase.BACKOFF: _backoff,
        Phase.RELEASE: _release,
        Phase.RETRACT: _retract,
    }

    # -- helpers ---------------------------------------------------------------------------

    def _next_stage(self, obs: Observation, name: str) -> None:
        self._stage.name = name
        self._stage.since_t_s = obs.t_s
        self._stage.count = 0

    def _planar(self, offset_uv: np.ndarray) -> np.ndarray:
        """A (u, v) offset in the opening's frame as a vector in B."""
        return self._hole_yaw.apply([offset_uv[0], offset_uv[1], 0.0])

    def _torque_tolerance(self) -> np.ndarray:
        """ALIGN's tolerances on the normalised torques (tau_x, tau_y, tau_z), noise units."""
        settings = self.config.align
        return np.array(
            [settings.tol_tau_x_sigma, settings.tol_tau_y_sigma, settings.tol_tau_z_sigma]
        )

    def _torques_within_tolerance(self) -> bool:
        return bool(np.all(np.abs(self.signals.normalised[:3]) <= self._torque_tolerance()))

    def _align_rate(self, rotation: Rotation, scale: float) -> np.ndarray:
        """Angular velocity in B yielding to the torques outside tolerance: w_T = -R_S2T k
        n_S, scaled (config.AlignSettings); at ``align.servo_tilt_max_rad`` from straight
        down or more, without the part that would tilt the TCP further."""
        settings = self.config.align
        gains = np.array([settings.gain_tau_x, settings.gain_tau_y, settings.gain_tau_z])
        tolerance = self._torque_tolerance()
        torque_s = self.signals.normalised[:3]
        outside = np.where(np.abs(torque_s) > tolerance, torque_s, 0.0)
        w = rotation.apply(-self.signals.s2t @ (gains * outside) * scale)
        angle, upright = tilt_of_tool_axis(tool_z_in_base(rotation))  # w along it: uprights
        if angle >= settings.servo_tilt_max_rad:
            w = w - min(0.0, float(w @ upright)) * upright
        return w

    def _search_rotation(self) -> Rotation:
        """The approach rotation, turned about B's z by the present pass's yaw once SEARCH
        has run out of time (config.SearchSettings, ``retry_yaw_rad``)."""
        start, length = self._yaw_passes_from_m, self._pattern.length_m
        if start is None or length <= 0.0:
            return self._approach_rot
        passes = int((self._search_s_m - start) // length)
        yaw = self.config.search.retry_yaw_rad * (1.0, -1.0, 0.0)[passes % 3]
        return Rotation.from_euler("z", yaw) * self._approach_rot

    def _hold_rotation(self, rotation: Rotation) -> np.ndarray:
        """Angular velocity in B servoing the TCP to the search rotation."""
        settings = self.config.approach
        return clamp_norm(
            settings.pose_gain_1_s * rotation_error(rotation, self._search_rotation()),
            settings.rotate_speed_rad_s,
        )

    def _tip_command(self, obs: Observation, v_tip: np.ndarray, w: np.ndarray) -> Command:
        """The command moving the tip at ``v_tip`` while turning at ``w`` (both in B)."""
        p_tcp = np.asarray(obs.arm.tcp.xyz_m, dtype=float)
        p_tip = tip_position(obs.arm.tcp, self.plug.length_m)
        v_tcp, w = pivot_twist(p_tcp, p_tip, v_tip, w)
        return self._command(v_tcp, w)

    def _tcp_twist(self, v: np.ndarray) -> Command:
        return self._command(v, np.zeros(3))

    def _command(self, v: np.ndarray, w: np.ndarray) -> Command:
        limits = self.config.limits
        return Command(
            twist=bounded_twist(v, w, limits.max_linear_speed_m_s, limits.max_angular_speed_rad_s)
        )

    def _capture_open(self, obs: Observation) -> Command:
        """Capture the open gel; the fingers (if wider) travel fast to just above the plug."""
        gripper = self.config.gripper.preclose_target(self.plug.thickness_m, obs.gripper.width_m)
        return Command(twist=Twist(), gripper=gripper, capture_open_tactile=True)

    def _close_target(self) -> GripperTarget:
        return close_target(self.config)

    def _open_target(self, width_m: float) -> GripperTarget:
        return open_target(self.config, width_m)


def close_target(config: MachineConfig) -> GripperTarget:
    """The gripper's close command (``gripper.close_*``)."""
    g = config.gripper
    return GripperTarget(g.close_width_m, g.close_speed_m_s, g.close_force_n)


def open_target(config: MachineConfig, width_m: float) -> GripperTarget:
    """The gripper's open command to ``width_m`` (m)."""
    g = config.gripper
    return GripperTarget(width_m, g.open_speed_m_s, g.close_force_n)


def operator_command(teleop: TeleopInput, config: MachineConfig) -> Command:
    """The operator's command in TELEOP: the pad's twist (TCP, in B) bounded by the
    machine's ``limits`` speeds, and a gripper target on a gripper button's press."""
    limits = config.limits
    twist = bounded_twist(
        np.asarray(teleop.twist.linear_m_s),
        np.asarray(teleop.twist.angular_rad_s),
        limits.max_linear_speed_m_s,
        limits.max_angular_speed_rad_s,
    )
    gripper = None
    if teleop.gripper_close:
        gripper = close_target(config)
    elif teleop.gripper_open:
        gripper = open_target(config, config.gripper.open_width_m)
    return Command(twist=twist, gripper=gripper)


def _hold() -> Command:
    """Hold still: a zero twist."""
    return Command(twist=Twist())


def _yaw_of(rotation: Rotation) -> float:
    """The heading (rad) of T x in B's x-y plane."""
    x_t = rotation.apply([1.0, 0.0, 0.0])
    return math.atan2(float(x_t[1]), float(x_t[0]))


def has_fault(obs: Observation) -> bool:
    """A device fault this tick: the loop's, the arm's error code or the gripper's."""
    return obs.fault is not None or obs.arm.error_code != 0 or obs.gripper.fault_code != 0
