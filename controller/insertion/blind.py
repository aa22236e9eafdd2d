"""The blind baseline: the strongest search an integrator would build without touch; and
the same search by touch (``touch_spiral``).

A force-threshold spiral with yaw steps on the arm's own status: the TCP pose and the force
of the F/T sensor at the flange (``ArmStatus.external_force_n``, in B; the arm file's
``ft_sensor``). No tactile signal. The touch spiral (``TouchSpiralConfig``, the task's
``touch_spiral:`` section) runs the same machine on the tactile estimate instead of the
F/T sensor (controller/insertion/force_reading.py: the plug's axial force); its grasp
captures the open gel before closing and re-zeroes the estimator after.

It grasps (close and settle), moves the plug upright above the nominal opening and, for
each yaw in ``yaw_offsets`` (0, +step, -step, +2 step, ... within ``yaw_range_rad``; the
connectors' clearances leave about a degree):

* **tare**: holds still at ``hover_m`` above the board for ``tare_s`` and takes the mean force
  as the sensor's zero (the F/T sensor drifts; the integrator tares before each contact);
* **touch**: descends at ``descend_speed_m_s`` until the tared upward force F (z in B)
  reaches ``touch_force_n``;
* **sweep**: runs the search pattern (``SearchPattern``, spiral or raster over the pose
  uncertainty) at ``sweep_speed_m_s`` while an admittance on z holds the press:
  v_z = ``force_gain_m_s_n`` x (F - ``press_force_n``). The press's height (the TCP's when F
  first settles within ``settle_band`` of the press) is the reference. When F falls below
  ``catch_ratio`` x the press (the tip over the opening) the pattern pauses (**probe**) and the
  admittance lowers the TCP; once the tip is ``catch_drop_m`` below its height at the press
  (the TCP's drop less the wrist's compression, F - press over ``wrist_z_stiffness_n_m``) it
  is caught (INSERT); if F recovers first, or after ``probe_s``, the pattern goes on;
* **insert**: holds the caught x, y and pushes down at ``push_speed_m_s`` until F reaches
  ``stop_force_n`` or the TCP stops going lower for ``stall_s`` (the arm's workspace
  floor): ``entry_m`` or more below the reference the plug is in (RELEASE,
  ``bottomed``: the push ends on the receptacle's floor or the plug's shoulder, however long
  the plug sticks out of the grasp); less, it jammed on the rim: it lifts back to the press
  and the pattern goes on ``jam_skip_m`` further along (``jammed``).

After the last yaw's pattern it releases and retracts (``pattern_done``). A trial scores it as
every controller (evaluation/trials/trial.py): DONE with the tip at the depth at some time.
Every command names its rule (``blind.tare``, ``blind.touch``, ``blind.sweep``,
``blind.probe``, ``blind.push``, ...), recorded with each tick.

Phases: GRASP -> APPROACH -> SEARCH <-> INSERT -> RELEASE -> RETRACT -> DONE; FAILED on a
device fault, the timeout, or an arm without a force reading (``device_fault``, its rule
``no_force``: the arm file's ``ft_sensor`` is off). The baseline ignores the gamepad (it runs
only in batch comparisons).
"""

from __future__ import annotations

import math
from collections import deque
from typing import Literal

import numpy as np
from scipy.spatial.transform import Rotation

from controller.insertion.definition import Definition, Edge, check_definition
from controller.insertion.force_reading import ArmForce, ForceReading
from controller.insertion.interface import (
    Command,
    FailureReason,
    GripperTarget,
    Observation,
    Phase,
    Transition,
)
from controller.insertion.machine_config import GripperSettings
from controller.insertion.motion import bounded_twist, rotation_error
from controller.insertion.search_path import SearchPattern
from core.config import Config, config_dataclass, number
from core.devices import Twist
from core.spatial import clamp_norm, rotation_from_rpy
from core.task_geometry import HolePose, PlugGeometry


@config_dataclass
class BlindConfig(Config):
    """The task file's ``blind:`` section. Lengths in m, speeds in m/s, angles in rad, forces
    in N (the tared upward force on the tool, z in B), times in s.

    ``pattern``, ``pitch_m``, ``half_width_m``: the search pattern (as ``machine.search``);
    ``touch_force_n``: the board is met; ``press_force_n``: held while sweeping;
    ``force_gain_m_s_n``: the admittance, z speed per N of force error; ``force_window``: the
    force is the mean of this many readings; ``wrist_z_stiffness_n_m``: the compliant
    wrist's axial stiffness, as the integrator measures it on the cell (the tip's drop is
    the TCP's less the wrist's compression); ``settle_band``: the press has settled within
    this share of it; ``catch_ratio``: the force under this share of the press pauses the
    pattern; ``catch_drop_m``: the tip this far below its height at the press is a catch;
    ``probe_s``: the longest a pause lasts; ``push_speed_m_s``, ``stop_force_n``: the push
    and the force that ends it; ``stall_s``: a push whose TCP has gone no lower for this
    long has ended too (the arm's own limit); ``entry_m``: the least drop of the tip below
    its height at the press that counts as in; ``jam_skip_m``: after a jam the pattern goes
    on this much further along; ``tare_s``: the sensor's zero is averaged over this at the
    hover; ``sweep_speed_m_s``: along the path; ``descend_speed_m_s``: down to the touch;
    ``yaw_step_rad``, ``yaw_range_rad``: the passes' yaw offsets (``yaw_offsets``);
    ``hover_m``: tip height above the board between passes; ``move_speed_m_s``,
    ``rotate_speed_rad_s``; ``pose_gain_1_s``: servo gain (speed = gain x error),
    ``pose_tol_m``: a target counts as reached within this; ``retract_m``;
    ``timeout_s``: the whole run; ``rewind``: a probe first takes the pattern back to where
    it was at the time the force's reading describes (the force's delay, swept past the
    opening), once per stretch of the pattern."""

    gripper: GripperSettings
    pattern: Literal["spiral", "raster"] = "spiral"
    pitch_m: float = number(1e-5, 0.01, default=0.0004)
    half_width_m: float = number(0.0, 0.05, default=0.003)
    touch_force_n: float = number(0.05, 50.0, default=1.0)
    press_force_n: float = number(0.05, 50.0, default=2.0)
    force_gain_m_s_n: float = number(1e-5, 0.05, default=0.005)
    force_window: int = number(1, 100, default=5)
    wrist_z_stiffness_n_m: float = number(10.0, 1e6, default=1000.0)
    settle_band: float = number(0.01, 1.0, default=0.2)
    catch_ratio: float = number(0.0, 1.0, default=0.4)
    catch_drop_m: float = number(1e-5, 0.02, default=0.001)
    probe_s: float = number(0.01, 10.0, default=0.5)
    push_speed_m_s: float = number(1e-4, 0.05, default=0.004)
    stop_force_n: float = number(0.1, 100.0, default=8.0)
    stall_s: float = number(0.01, 10.0, default=0.3)
    entry_m: float = number(0.0, 0.05, default=0.002)
    jam_skip_m: float = number(0.0, 0.05, default=0.001)
    tare_s: float = number(0.0, 5.0, default=0.2)
    sweep_speed_m_s: float = number(1e-4, 0.1, default=0.01)
    descend_speed_m_s: float = number(1e-4, 0.1, default=0.005)
    yaw_step_rad: float = number(1e-4, 0.5, default=0.02)
    yaw_range_rad: float = number(0.0, 0.5, default=0.0524)
    hover_m: float = number(0.0, 0.05, default=0.002)
    move_speed_m_s: float = number(1e-4, 0.2, default=0.02)
    pose_gain_1_s: float = number(0.1, 100.0, default=10.0)
    rotate_speed_rad_s: float = number(1e-3, 3.0, default=0.5)
    pose_tol_m: float = number(1e-6, 0.01, default=0.0002)
    retract_m: float = number(0.0, 0.2, default=0.03)
    timeout_s: float = number(1.0, 3600.0, default=120.0)
    rewind: bool = False

    def __post_init__(self) -> None:
        if not self.touch_force_n < self.press_force_n < self.stop_force_n:
            raise ValueError(
                "keys 'touch_force_n', 'press_force_n', 'stop_force_n': expected increasing "
                f"forces, got {self.touch_force_n}, {self.press_force_n}, {self.stop_force_n}"
            )

    @property
    def yaw_offsets(self) -> tuple[float, ...]:
        """The passes' yaw offsets from the nominal, rad: 0, +step, -step, +2 step, -2 step,
        ... while within ``yaw_range_rad``."""
        steps = int(math.floor(self.yaw_range_rad / self.yaw_step_rad + 1e-9))
        offsets = [0.0]
        for k in range(1, steps + 1):
            offsets += [k * self.yaw_step_rad, -k * self.yaw_step_rad]
        return tuple(offsets)


AxialWeights = tuple[float, float, float, float, float, float, float, float, float]


@config_dataclass
class TouchSpiralConfig(BlindConfig):
    """The task file's ``touch_spiral:`` section: the blind baseline's search with the force
    read by touch (``force_reading.TactileAxialForce``), every key as ``blind:``'s, forces
    on the whole plug; ``axial_weights``: N on the plug per unit of each of the estimate's
    ``force_reading.AXIAL_TERMS`` (nine: tau_x, tau_y, tau_z in N*m, shear_x, shear_y,
    normal in N, the three torques' magnitudes). The default reads the force channel along
    T z (S's shear_y) over the sensing finger's share of the load (two alike fingers).
    ``force_window`` counts tactile frames here, and the force is their median."""

    axial_weights: AxialWeights = (0.0, 0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 0.0)


LEAD_S = 0.01  # the sweep's velocity is the target's over this time ahead, s
TURN_TOL_RAD = 0.002  # a pass's yaw is reached within this, rad
STALL_M = 1e-4  # the push is moving while the TCP goes this much lower within stall_s, m
HISTORY_TICKS = 100  # the sweep's (time, length) kept for a rewind: 1 s at 100 Hz
OPEN_FRAMES = 6  # new frames seen while the estimator takes the open gel (more than it takes)
NO_FORCE = "no_force"  # the FAILED transition's rule when the arm reports no force

F = FailureReason
BLIND = Definition(
    phases=(
        Phase.GRASP,
        Phase.APPROACH,
        Phase.SEARCH,
        Phase.INSERT,
        Phase.RELEASE,
        Phase.RETRACT,
        Phase.DONE,
        Phase.FAILED,
    ),  # fmt: skip
    initial=Phase.GRASP,
    terminal=(Phase.DONE, Phase.FAILED),
    edges=(
        Edge(Phase.GRASP, Phase.APPROACH, "grasped"),
        Edge(Phase.APPROACH, Phase.SEARCH, "above_the_opening"),
        Edge(Phase.SEARCH, Phase.INSERT, "caught"),
        Edge(Phase.INSERT, Phase.SEARCH, "jammed"),
        Edge(Phase.INSERT, Phase.RELEASE, "bottomed"),
        Edge(Phase.SEARCH, Phase.RELEASE, "pattern_done"),
        Edge(Phase.RELEASE, Phase.RETRACT, "released"),
        Edge(Phase.RETRACT, Phase.DONE, "retracted"),
        *(
            Edge(source, Phase.FAILED, reason.value)
            for source in (
                Phase.GRASP,
                Phase.APPROACH,
                Phase.SEARCH,
                Phase.INSERT,
                Phase.RELEASE,
                Phase.RETRACT,
            )  # fmt: skip
            for reason in (F.TIMEOUT, F.DEVICE_FAULT)
        ),
    ),
)


class BlindMachine:
    """The blind baseline (see the module doc); a ``Machine`` for the control loop."""

    def __init__(
        self,
        config: BlindConfig,
        plug: PlugGeometry,
        hole: HolePose,
        reading: ForceReading | None = None,
    ) -> None:
        check_definition(BLIND)
        self.config, self.plug, self.hole = config, plug, hole
        self._reading = reading if reading is not None else ArmForce(config.force_window)
        self._force_n = 0.0  # the reading's last force (N) and the time it describes (s)
        self._force_t_s = 0.0
        self._frames = 0  # new tactile estimates counted while capturing the open gel
        self._frame_t_s = math.nan
        self._phase = Phase.GRASP
        self._transitions: list[Transition] = []
        self._pattern = SearchPattern(config.pattern, config.pitch_m, config.half_width_m)
        self._yaws = config.yaw_offsets
        self._start_t_s: float | None = None
        self._since_t_s = 0.0
        self._last_t_s = 0.0
        self._stage = ""
        self._pass = 0
        self._s_m = 0.0  # the pattern's path length swept in this pass
        self._s_history: deque[tuple[float, float]] = deque(maxlen=HISTORY_TICKS)
        self._rewound_to_m = -math.inf  # the pattern's length at the last rewound probe
        self._tare: list[float] = []
        self._bias_n = 0.0
        self._press_z_m: float | None = None  # the TCP's height at the settled press
        self._hold_xy: np.ndarray | None = None  # INSERT's x, y (the TCP's at the catch)
        self._stall_z_m = math.inf  # the push's lowest TCP height so far, and when
        self._stall_t_s = 0.0
        self._z0_m = 0.0

    @property
    def phase(self) -> Phase:
        return self._phase

    @property
    def transitions(self) -> tuple[Transition, ...]:
        return tuple(self._transitions)

    def step(self, obs: Observation) -> Command:
        if self._phase in (Phase.DONE, Phase.FAILED):
            return Command(twist=Twist())
        if self._start_t_s is None:
            self._start_t_s = self._last_t_s = obs.t_s
        dt_s, self._last_t_s = obs.t_s - self._last_t_s, obs.t_s
        if obs.fault or obs.arm.error_code or obs.gripper.fault_code:
            return self._go(obs, Phase.FAILED, F.DEVICE_FAULT.value)
        if not self._reading.available(obs):
            return self._go(obs, Phase.FAILED, F.DEVICE_FAULT.value, NO_FORCE)
        if obs.t_s - self._start_t_s > self.config.timeout_s:
            return self._go(obs, Phase.FAILED, F.TIMEOUT.value)
        if self._phase is Phase.SEARCH:
            return self._search(obs, dt_s)
        return getattr(self, f"_{self._phase.value}")(obs)

    # -- phases ------------------------------------------------------------------------------

    def _grasp(self, obs: Observation) -> Command:
        g = self.config.gripper
        zeroes = self._reading.zeroes_tactile
        if self._stage == "":  # fast to just above the plug, then close slowly
            self._stage = "preclose"
            target = g.preclose_target(self.plug.thickness_m, obs.gripper.width_m)
            if target is not None or zeroes:
                return Command(
                    twist=Twist(), gripper=target, capture_open_tactile=zeroes,
                    rule="grasp.preclose",
                )  # fmt: skip
        if self._stage == "preclose":
            if obs.wrench is not None and obs.wrench.t_s != self._frame_t_s:
                self._frame_t_s, self._frames = obs.wrench.t_s, self._frames + 1
            if obs.gripper.moving or (zeroes and self._frames <= OPEN_FRAMES):
                return Command(twist=Twist(), rule="grasp.preclose")
            self._stage, self._since_t_s = "settle", obs.t_s
            return Command(
                twist=Twist(),
                gripper=GripperTarget(g.close_width_m, g.close_speed_m_s, g.close_force_n),
                rule="grasp.close",
            )
        if not (obs.gripper.holding and not obs.gripper.moving):
            self._since_t_s = obs.t_s
        elif obs.t_s - self._since_t_s >= g.settle_s:
            if zeroes:  # the new reference is taken in the air on the way (the tare waits)
                self._go(obs, Phase.APPROACH, "grasped")
                return Command(twist=Twist(), rezero_tactile=True, rule="grasp.zero")
            return self._go(obs, Phase.APPROACH, "grasped")
        return Command(twist=Twist(), rule="grasp.close")

    def _approach(self, obs: Observation) -> Command:
        target = self._tip_target(0.0, self.config.hover_m)
        if self._reach(obs, target):
            return self._go(obs, Phase.SEARCH, "above_the_opening")
        return self._servo(obs, target, rule="approach.move")

    def _search(self, obs: Observation, dt_s: float) -> Command:
        """Each pass: tare, touch, the pressed sweep with its probes, up to the hover height;
        then the next yaw's pass, or the release after the last."""
        cfg = self.config
        stage = self._stage or "tare"
        self._stage = stage
        if stage == "tare":  # over readings only (the tactile one is none while zeroing)
            if self._read_force(obs):
                self._tare.append(self._force_n)
            if obs.t_s - self._since_t_s >= cfg.tare_s and self._tare:
                self._bias_n = float(np.mean(self._tare))
                self._tare, self._stage, self._press_z_m = [], "touch", None
            return self._servo(obs, self._tip_target(self._s_m, cfg.hover_m), rule="blind.tare")
        force = self._raw_force(obs) - self._bias_n
        if stage == "touch":
            if force >= cfg.touch_force_n:
                self._stage, self._since_t_s = "sweep", obs.t_s
                return self._pressed(obs, force, rule="blind.touch")
            return self._descend(obs, cfg.descend_speed_m_s, rule="blind.touch")
        if stage in ("sweep", "probe"):
            return self._sweep_or_probe(obs, force, dt_s)
        if stage == "turn":  # to the pattern's start at the next yaw
            target = self._tip_target(0.0, cfg.hover_m)
            if self._reach(obs, target) and self._turned(obs):
                self._stage, self._since_t_s = "tare", obs.t_s
            return self._servo(obs, target, rule="blind.turn")
        target = self._tip_target(self._s_m, cfg.hover_m)  # rise
        if self._reach(obs, target):
            if self._pass + 1 >= len(self._yaws):
                return self._go(obs, Phase.RELEASE, "pattern_done")
            self._pass, self._s_m = self._pass + 1, 0.0
            self._stage = "turn"
        return self._servo(obs, target, rule="blind.rise")

    def _sweep_or_probe(self, obs: Observation, force: float, dt_s: float) -> Command:
        cfg = self.config
        z = obs.arm.tcp.xyz_m[2]
        if self._press_z_m is None and abs(force - cfg.press_force_n) <= (
            cfg.settle_band * cfg.press_force_n
        ):
            self._press_z_m = z
        if self._stage == "probe":
            if self._press_z_m is not None and self._tip_drop_m(obs, force) >= cfg.catch_drop_m:
                self._hold_xy = np.asarray(obs.arm.tcp.xyz_m[:2])
                return self._go(obs, Phase.INSERT, "caught")
            if force >= cfg.press_force_n or obs.t_s - self._since_t_s >= cfg.probe_s:
                self._stage = "sweep"
            return self._pressed(obs, force, rule="blind.probe")
        if self._press_z_m is not None and force < cfg.catch_ratio * cfg.press_force_n:
            self._stage, self._since_t_s = "probe", obs.t_s
            if cfg.rewind and self._s_m > self._rewound_to_m:
                self._rewound_to_m = self._s_m
                self._s_m = self._s_at(self._force_t_s)
            return self._pressed(obs, force, rule="blind.probe")
        self._s_m += cfg.sweep_speed_m_s * dt_s
        self._s_history.append((obs.t_s, self._s_m))
        if self._s_m >= self._pattern.length_m:
            self._stage = "rise"
        return self._pressed(obs, force, moving=True, rule="blind.sweep")

    def _insert(self, obs: Observation) -> Command:
        cfg = self.config
        force = self._raw_force(obs) - self._bias_n
        if self._stage == "lift":  # back to the press after a jam, then the sweep goes on
            if force <= cfg.press_force_n:
                self._go(obs, Phase.SEARCH, "jammed")
                self._stage, self._s_m = "sweep", self._s_m + cfg.jam_skip_m
                return self._pressed(obs, force, rule="blind.lift")
            return self._descend(obs, -cfg.push_speed_m_s, rule="blind.lift", hold=True)
        z = obs.arm.tcp.xyz_m[2]
        if self._stage == "" or z < self._stall_z_m - STALL_M:
            self._stage, self._stall_z_m, self._stall_t_s = "push", z, obs.t_s
        stalled = obs.t_s - self._stall_t_s >= cfg.stall_s
        if force >= cfg.stop_force_n or stalled:
            assert self._press_z_m is not None  # set before any catch
            if self._tip_drop_m(obs, force) >= cfg.entry_m:
                return self._go(obs, Phase.RELEASE, "bottomed", "stall" if stalled else "force")
            self._stage = "lift"
            return self._descend(obs, -cfg.push_speed_m_s, rule="blind.lift", hold=True)
        return self._descend(obs, cfg.push_speed_m_s, rule="blind.push", hold=True)

    def _release(self, obs: Observation) -> Command:
        g = self.config.gripper
        if self._stage == "":
            self._stage, self._since_t_s = "open", obs.t_s
            return Command(
                twist=Twist(),
                gripper=GripperTarget(g.open_width_m, g.open_speed_m_s, g.close_force_n),
                rule="release.open",
            )
        if obs.t_s - self._since_t_s >= g.settle_s and not obs.gripper.moving:
            self._z0_m = obs.arm.tcp.xyz_m[2]
            return self._go(obs, Phase.RETRACT, "released")
        return Command(twist=Twist(), rule="release.open")

    def _retract(self, obs: Observation) -> Command:
        if obs.arm.tcp.xyz_m[2] >= self._z0_m + self.config.retract_m:
            return self._go(obs, Phase.DONE, "retracted")
        return Command(twist=Twist((0.0, 0.0, self.config.move_speed_m_s)), rule="retract.lift")

    # -- helpers -----------------------------------------------------------------------------

    def _go(self, obs: Observation, target: Phase, reason: str, rule: str = "") -> Command:
        if not BLIND.allows(self._phase, target, reason):
            raise RuntimeError(f"blind machine: no edge {self._phase} -> {target} ({reason})")
        self._transitions.append(Transition(obs.t_s, self._phase, target, reason, rule))
        self._phase, self._stage, self._since_t_s = target, "", obs.t_s
        return Command(twist=Twist())

    def _read_force(self, obs: Observation) -> bool:
        """Take the reading's newest force and its time, if it has one (True)."""
        reading = self._reading.read(obs)
        if reading is not None:
            self._force_n, self._force_t_s = reading
        return reading is not None

    def _raw_force(self, obs: Observation) -> float:
        """The upward force on the tool (z in B), N, untared: the reading's newest (its last
        while it has none)."""
        self._read_force(obs)
        return self._force_n

    def _s_at(self, t_s: float) -> float:
        """The pattern's swept length at time ``t_s`` (the earliest kept, if older)."""
        for t, s_m in reversed(self._s_history):
            if t <= t_s:
                return s_m
        return self._s_history[0][1] if self._s_history else self._s_m

    def _tip_drop_m(self, obs: Observation, force: float) -> float:
        """How far the tip has gone below its height at the settled press, m: the TCP's drop
        less the wrist's extra compression (force above the press over its stiffness)."""
        assert self._press_z_m is not None
        cfg = self.config
        tcp_drop = self._press_z_m - obs.arm.tcp.xyz_m[2]
        return tcp_drop - (force - cfg.press_force_n) / cfg.wrist_z_stiffness_n_m

    def _upright(self) -> Rotation:
        """The tool's orientation for this pass: upright, at the pass's yaw."""
        yaw = self.hole.yaw_rad + self._yaws[self._pass]
        return Rotation.from_euler("z", yaw) * Rotation.from_euler("x", math.pi)

    def _tip_target(self, s_m: float, height_m: float) -> np.ndarray:
        """The tip's target in B at path length ``s_m`` of the pattern, ``height_m`` above the
        nominal board."""
        u, v = self._pattern.offset(s_m)
        planar = Rotation.from_euler("z", self.hole.yaw_rad).apply([u, v, 0.0])
        return np.array([self.hole.x_m, self.hole.y_m, self.hole.z_m + height_m]) + planar

    def _tcp_target(self, tip: np.ndarray) -> np.ndarray:
        return tip - self._upright().apply([0.0, 0.0, self.plug.length_m])

    def _reach(self, obs: Observation, tip: np.ndarray) -> bool:
        error = self._tcp_target(tip) - np.asarray(obs.arm.tcp.xyz_m)
        return bool(np.linalg.norm(error) <= self.config.pose_tol_m)

    def _turned(self, obs: Observation) -> bool:
        turn = rotation_error(rotation_from_rpy(obs.arm.tcp.rpy_rad), self._upright())
        return bool(np.linalg.norm(turn) <= TURN_TOL_RAD)

    def _pressed(self, obs: Observation, force: float, rule: str, moving: bool = False) -> Command:
        """x, y on the pattern at the swept length (its velocity ahead when ``moving``), z by
        the admittance on the press."""
        cfg = self.config
        now = self._tcp_target(self._tip_target(self._s_m, 0.0))
        v = cfg.pose_gain_1_s * (now - np.asarray(obs.arm.tcp.xyz_m))
        if moving:
            ahead = self._tcp_target(
                self._tip_target(self._s_m + cfg.sweep_speed_m_s * LEAD_S, 0.0)
            )
            v += (ahead - now) / LEAD_S
        v[2] = cfg.force_gain_m_s_n * (force - cfg.press_force_n)
        return self._command(obs, v, cfg.move_speed_m_s, rule)

    def _descend(
        self, obs: Observation, speed_m_s: float, rule: str, hold: bool = False
    ) -> Command:
        """Down at ``speed_m_s`` (up when negative), x, y held on the pattern's point (or at
        the catch's with ``hold``)."""
        cfg = self.config
        if hold and self._hold_xy is not None:
            xy = self._hold_xy
        else:
            xy = self._tcp_target(self._tip_target(self._s_m, 0.0))[:2]
        v = np.zeros(3)
        v[:2] = cfg.pose_gain_1_s * (xy - np.asarray(obs.arm.tcp.xyz_m[:2]))
        v[2] = -speed_m_s
        return self._command(obs, v, cfg.move_speed_m_s, rule)

    def _servo(self, obs: Observation, tip: np.ndarray, rule: str) -> Command:
        cfg = self.config
        error = self._tcp_target(tip) - np.asarray(obs.arm.tcp.xyz_m)
        return self._command(obs, cfg.pose_gain_1_s * error, cfg.move_speed_m_s, rule)

    def _command(self, obs: Observation, v: np.ndarray, speed_m_s: float, rule: str) -> Command:
        cfg = self.config
        v = clamp_norm(v, speed_m_s)
        turn = rotation_error(rotation_from_rpy(obs.arm.tcp.rpy_rad), self._upright())
        w = clamp_norm(cfg.pose_gain_1_s * turn, cfg.rotate_speed_rad_s)
        twist = bounded_twist(v, w, cfg.move_speed_m_s, cfg.rotate_speed_rad_s)
        return Command(twist=twist, rule=rule)
