"""The blind baseline: the strongest search an integrator would build without touch.

It grasps (close and settle, no tactile zeroing), moves the plug upright above the nominal
opening and then sweeps the search pattern (``SearchPattern``: spiral or raster over the
pose uncertainty) *pressed*: the tip target is ``press_m`` below the board surface, so the
compliant wrist's spring holds the tip on the board with a light, bounded force and, where
the tip passes over the opening, pushes it in (passive compliance: the classic force-
limited spiral search, with the wrist's spring in place of a force loop). The sweep is
continuous, at ``sweep_speed_m_s`` along the path. The opening's yaw is uncertain and the
connectors' clearances leave about a degree, so the pattern is swept once per yaw in
``yaw_offsets`` (0, +step, -step, +2 step, ... within ``yaw_range_rad``); between passes the
tip rises to ``hover_m`` and turns. After the last pass it releases and retracts.

It has no sensing but the arm's own status (the commanded pose the arm reports): it cannot
know when the plug went in, so it finishes its passes. A trial scores it as every
controller (evaluation/trials/trial.py): DONE and the tip reached the depth at some time,
which credits an insertion the sweep then dragged on from; so its success rate is an
optimistic bound on position-only search.

Phases: GRASP -> APPROACH -> SEARCH -> RELEASE -> RETRACT -> DONE; FAILED on a device fault
or the timeout. The baseline ignores the gamepad (it runs only in batch comparisons).
"""

from __future__ import annotations

import math
from typing import Literal

import numpy as np
from scipy.spatial.transform import Rotation

from controller.insertion.definition import Definition, Edge, check_definition
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
from controller.insertion.search import SearchPattern
from core.config import Config, config_dataclass, number
from core.devices import Twist
from core.spatial import clamp_norm, rotation_from_rpy
from core.task_geometry import HolePose, PlugGeometry


@config_dataclass
class BlindConfig(Config):
    """The task file's ``blind:`` section. Lengths in m, speeds in m/s, angles in rad, times
    in s.

    ``pattern``, ``pitch_m``, ``half_width_m``: the search pattern (as ``machine.search``);
    ``press_m``: the tip target below the board surface while sweeping (the wrist's spring
    takes it up on the board: the press; in the opening: the push to the depth);
    ``sweep_speed_m_s``: along the path; ``descend_speed_m_s``: down to the press, from
    the hover height (slow: the tip meets the board on the way); ``yaw_step_rad``,
    ``yaw_range_rad``: the yaw offsets of the passes (``yaw_offsets``); ``hover_m``: tip
    height above the board between passes;
    ``move_speed_m_s``, ``rotate_speed_rad_s``; ``pose_gain_1_s``: servo gain (speed = gain
    x error), ``pose_tol_m``: a target counts as reached within this; ``retract_m``;
    ``timeout_s``: the whole run."""

    gripper: GripperSettings
    pattern: Literal["spiral", "raster"] = "spiral"
    pitch_m: float = number(1e-5, 0.01, default=0.0004)
    half_width_m: float = number(0.0, 0.05, default=0.003)
    press_m: float = number(0.0, 0.05, default=0.006)
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

    @property
    def yaw_offsets(self) -> tuple[float, ...]:
        """The passes' yaw offsets from the nominal, rad: 0, +step, -step, +2 step, -2 step,
        ... while within ``yaw_range_rad``."""
        steps = int(math.floor(self.yaw_range_rad / self.yaw_step_rad + 1e-9))
        offsets = [0.0]
        for k in range(1, steps + 1):
            offsets += [k * self.yaw_step_rad, -k * self.yaw_step_rad]
        return tuple(offsets)


LEAD_S = 0.01  # the sweep's velocity is the target's over this time ahead, s
TURN_TOL_RAD = 0.002  # a pass's yaw is reached within this, rad

F = FailureReason
BLIND = Definition(
    phases=(
        Phase.GRASP,
        Phase.APPROACH,
        Phase.SEARCH,
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
        Edge(Phase.SEARCH, Phase.RELEASE, "pattern_done"),
        Edge(Phase.RELEASE, Phase.RETRACT, "released"),
        Edge(Phase.RETRACT, Phase.DONE, "retracted"),
        *(
            Edge(source, Phase.FAILED, reason.value)
            for source in (
                Phase.GRASP,
                Phase.APPROACH,
                Phase.SEARCH,
                Phase.RELEASE,
                Phase.RETRACT,
            )  # fmt: skip
            for reason in (F.TIMEOUT, F.DEVICE_FAULT)
        ),
    ),
)


class BlindMachine:
    """The blind baseline (see the module doc); a ``Machine`` for the control loop."""

    def __init__(self, config: BlindConfig, plug: PlugGeometry, hole: HolePose) -> None:
        check_definition(BLIND)
        self.config, self.plug, self.hole = config, plug, hole
        self._phase = Phase.GRASP
        self._transitions: list[Transition] = []
        self._pattern = SearchPattern(config.pattern, config.pitch_m, config.half_width_m)
        self._yaws = config.yaw_offsets
        self._start_t_s: float | None = None
        self._since_t_s = 0.0
        self._stage = ""
        self._pass = 0
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
            self._start_t_s = obs.t_s
        if obs.fault or obs.arm.error_code or obs.gripper.fault_code:
            return self._go(obs, Phase.FAILED, F.DEVICE_FAULT.value)
        if obs.t_s - self._start_t_s > self.config.timeout_s:
            return self._go(obs, Phase.FAILED, F.TIMEOUT.value)
        return getattr(self, f"_{self._phase.value}")(obs)

    # -- phases ------------------------------------------------------------------------------

    def _grasp(self, obs: Observation) -> Command:
        g = self.config.gripper
        if self._stage == "":  # fast to just above the plug, then close slowly
            self._stage = "preclose"
            target = g.preclose_target(self.plug.thickness_m, obs.gripper.width_m)
            if target is not None:
                return Command(twist=Twist(), gripper=target)
        if self._stage == "preclose":
            if obs.gripper.moving:
                return Command(twist=Twist())
            self._stage, self._since_t_s = "settle", obs.t_s
            return Command(
                twist=Twist(),
                gripper=GripperTarget(g.close_width_m, g.close_speed_m_s, g.close_force_n),
            )
        if not (obs.gripper.holding and not obs.gripper.moving):
            self._since_t_s = obs.t_s
        elif obs.t_s - self._since_t_s >= g.settle_s:
            return self._go(obs, Phase.APPROACH, "grasped")
        return Command(twist=Twist())

    def _approach(self, obs: Observation) -> Command:
        target = self._tip_target(0.0, self.config.hover_m)
        if self._reach(obs, target):
            return self._go(obs, Phase.SEARCH, "above_the_opening")
        return self._servo(obs, target)

    def _search(self, obs: Observation) -> Command:
        """Each pass: down to the press at the pattern's start, the pressed sweep, up to the
        hover height; then the next yaw's pass, or the release after the last."""
        cfg = self.config
        if self._stage == "":
            self._stage = "press"
        if self._stage == "press":
            target = self._tip_target(0.0, -cfg.press_m)
            if self._reach(obs, target):
                self._stage, self._since_t_s = "sweep", obs.t_s
            return self._servo(obs, target, cfg.descend_speed_m_s)
        if self._stage == "sweep":
            s_m = cfg.sweep_speed_m_s * (obs.t_s - self._since_t_s)
            if s_m >= self._pattern.length_m:
                self._stage = "rise"
            return self._sweep(obs, s_m)
        if self._stage == "turn":  # to the pattern's start at the next yaw
            target = self._tip_target(0.0, cfg.hover_m)
            if self._reach(obs, target) and self._turned(obs):
                self._stage = "press"
            return self._servo(obs, target)
        target = self._tip_target(self._pattern.length_m, cfg.hover_m)  # rise
        if self._reach(obs, target):
            if self._pass + 1 >= len(self._yaws):
                return self._go(obs, Phase.RELEASE, "pattern_done")
            self._pass += 1
            self._stage = "turn"
        return self._servo(obs, target)

    def _release(self, obs: Observation) -> Command:
        g = self.config.gripper
        if self._stage == "":
            self._stage, self._since_t_s = "open", obs.t_s
            return Command(
                twist=Twist(),
                gripper=GripperTarget(g.open_width_m, g.open_speed_m_s, g.close_force_n),
            )
        if obs.t_s - self._since_t_s >= g.settle_s and not obs.gripper.moving:
            self._z0_m = obs.arm.tcp.xyz_m[2]
            return self._go(obs, Phase.RETRACT, "released")
        return Command(twist=Twist())

    def _retract(self, obs: Observation) -> Command:
        if obs.arm.tcp.xyz_m[2] >= self._z0_m + self.config.retract_m:
            return self._go(obs, Phase.DONE, "retracted")
        return Command(twist=Twist((0.0, 0.0, self.config.move_speed_m_s)))

    # -- helpers -----------------------------------------------------------------------------

    def _go(self, obs: Observation, target: Phase, reason: str) -> Command:
        if not BLIND.allows(self._phase, target, reason):
            raise RuntimeError(f"blind machine: no edge {self._phase} -> {target} ({reason})")
        self._transitions.append(Transition(obs.t_s, self._phase, target, reason))
        self._phase, self._stage, self._since_t_s = target, "", obs.t_s
        return Command(twist=Twist())

    def _upright(self) -> Rotation:
        """The tool's orientation for this pass: upright, at the pass's yaw."""
        yaw = self.hole.yaw_rad + self._yaws[self._pass]
        return Rotation.from_euler("z", yaw) * Rotation.from_euler("x", math.pi)

    def _tip_target(self, s_m: float, height_m: float) -> np.ndarray:
        """The tip's target in B at path length ``s_m`` of the pattern, ``height_m`` above the
        board."""
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

    def _sweep(self, obs: Observation, s_m: float) -> Command:
        """Follow the pattern's moving target: its velocity ahead (finite difference over
        ``LEAD_S``) plus the servo's correction."""
        cfg = self.config
        now = self._tcp_target(self._tip_target(s_m, -cfg.press_m))
        ahead = self._tcp_target(self._tip_target(s_m + cfg.sweep_speed_m_s * LEAD_S, -cfg.press_m))
        v = (ahead - now) / LEAD_S + cfg.pose_gain_1_s * (now - np.asarray(obs.arm.tcp.xyz_m))
        return self._command(obs, v, cfg.move_speed_m_s)

    def _servo(self, obs: Observation, tip: np.ndarray, speed_m_s: float | None = None) -> Command:
        cfg = self.config
        error = self._tcp_target(tip) - np.asarray(obs.arm.tcp.xyz_m)
        return self._command(obs, cfg.pose_gain_1_s * error, speed_m_s or cfg.move_speed_m_s)

    def _command(self, obs: Observation, v: np.ndarray, speed_m_s: float) -> Command:
        cfg = self.config
        v = clamp_norm(v, speed_m_s)
        turn = rotation_error(rotation_from_rpy(obs.arm.tcp.rpy_rad), self._upright())
        w = clamp_norm(cfg.pose_gain_1_s * turn, cfg.rotate_speed_rad_s)
        return Command(twist=bounded_twist(v, w, cfg.move_speed_m_s, cfg.rotate_speed_rad_s))
