"""The blind baseline: position-only search with no tactile feedback (issue 13's ``blind``).

It grasps (close and settle, no tactile zeroing), moves the plug upright above the nominal
opening, then visits the points of the same search pattern as the tactile machine
(``SearchPattern``: spiral or raster over the pose uncertainty), ``step_m`` apart along the
path; at each point it pushes the tip down to ``push_depth_m`` below the board surface (the
compliant wrist absorbs the push where the tip meets the board), dwells, and rises to
``hover_m`` before the next point. After the last point it releases and retracts.

It never knows whether a push went in: it has no sensing but the arm's own (commanded) pose.
A trial scores it as every controller (evaluation/trials/trial.py): DONE and the tip
reached the depth at some time, which credits a push that went in even though the machine
then moved on; so its success rate is an optimistic bound on position-only search.

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
    """The task file's ``blind:`` section. Lengths in m, speeds in m/s, times in s.

    ``pattern``, ``pitch_m``, ``half_width_m``: the search pattern (as ``machine.search``);
    ``step_m``: distance along the path between pushes; ``hover_m``: tip height above the
    board between pushes; ``push_depth_m``: tip target below the board surface at a push;
    ``move_speed_m_s``, ``push_speed_m_s``, ``rotate_speed_rad_s``; ``pose_gain_1_s``: servo
    gain (speed = gain x error), ``pose_tol_m``: a target counts as reached within this;
    ``dwell_s``: hold at the bottom of a push; ``timeout_s``: the whole run."""

    gripper: GripperSettings
    pattern: Literal["spiral", "raster"] = "spiral"
    pitch_m: float = number(1e-5, 0.01, default=0.0004)
    half_width_m: float = number(0.0, 0.05, default=0.003)
    step_m: float = number(1e-5, 0.01, default=0.0004)
    hover_m: float = number(0.0, 0.05, default=0.002)
    push_depth_m: float = number(0.0, 0.05, default=0.006)
    move_speed_m_s: float = number(1e-4, 0.2, default=0.02)
    push_speed_m_s: float = number(1e-4, 0.2, default=0.02)
    pose_gain_1_s: float = number(0.1, 100.0, default=10.0)
    rotate_speed_rad_s: float = number(1e-3, 3.0, default=0.5)
    pose_tol_m: float = number(1e-6, 0.01, default=0.0002)
    dwell_s: float = number(0.0, 10.0, default=0.05)
    retract_m: float = number(0.0, 0.2, default=0.03)
    timeout_s: float = number(1.0, 3600.0, default=120.0)


F = FailureReason
BLIND = Definition(
    phases=(Phase.GRASP, Phase.APPROACH, Phase.SEARCH, Phase.RELEASE, Phase.RETRACT,
            Phase.DONE, Phase.FAILED),  # fmt: skip
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
            for source in (Phase.GRASP, Phase.APPROACH, Phase.SEARCH, Phase.RELEASE,
                           Phase.RETRACT)  # fmt: skip
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
        self._points = int(math.floor(self._pattern.length_m / config.step_m)) + 1
        self._upright = Rotation.from_euler("z", hole.yaw_rad) * Rotation.from_euler("x", math.pi)
        self._start_t_s: float | None = None
        self._since_t_s = 0.0
        self._stage = ""
        self._point = 0
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
        if self._reach(obs, self._tip_target(self._point, self.config.hover_m)):
            return self._go(obs, Phase.SEARCH, "above_the_opening")
        return self._servo(obs, self._tip_target(self._point, self.config.hover_m))

    def _search(self, obs: Observation) -> Command:
        cfg = self.config
        if self._stage == "":
            self._stage = "push"
        if self._stage == "push":
            target = self._tip_target(self._point, -cfg.push_depth_m)
            if self._reach(obs, target):
                self._stage, self._since_t_s = "dwell", obs.t_s
            return self._servo(obs, target, cfg.push_speed_m_s)
        if self._stage == "dwell":
            if obs.t_s - self._since_t_s >= cfg.dwell_s:
                self._stage = "rise"
            return Command(twist=Twist())
        target = self._tip_target(self._point, cfg.hover_m)  # rise, then move to the next
        if self._reach(obs, target):
            if self._stage == "rise":
                if self._point + 1 >= self._points:
                    return self._go(obs, Phase.RELEASE, "pattern_done")
                self._point += 1
                self._stage = "move"
            else:
                self._stage = "push"
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

    def _tip_target(self, point: int, height_m: float) -> np.ndarray:
        """The tip's target in B at pattern point ``point``, ``height_m`` above the board."""
        u, v = self._pattern.offset(point * self.config.step_m)
        planar = Rotation.from_euler("z", self.hole.yaw_rad).apply([u, v, 0.0])
        return np.array([self.hole.x_m, self.hole.y_m, self.hole.z_m + height_m]) + planar

    def _tcp_target(self, tip: np.ndarray) -> np.ndarray:
        return tip - self._upright.apply([0.0, 0.0, self.plug.length_m])

    def _reach(self, obs: Observation, tip: np.ndarray) -> bool:
        error = self._tcp_target(tip) - np.asarray(obs.arm.tcp.xyz_m)
        return bool(np.linalg.norm(error) <= self.config.pose_tol_m)

    def _servo(self, obs: Observation, tip: np.ndarray, speed_m_s: float | None = None) -> Command:
        cfg = self.config
        error = self._tcp_target(tip) - np.asarray(obs.arm.tcp.xyz_m)
        v = clamp_norm(cfg.pose_gain_1_s * error, speed_m_s or cfg.move_speed_m_s)
        turn = rotation_error(rotation_from_rpy(obs.arm.tcp.rpy_rad), self._upright)
        w = clamp_norm(cfg.pose_gain_1_s * turn, cfg.rotate_speed_rad_s)
        return Command(twist=bounded_twist(v, w, cfg.move_speed_m_s, cfg.rotate_speed_rad_s))
