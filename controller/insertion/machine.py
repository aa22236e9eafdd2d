"""The find-align-insert state machine (the ``align`` controller; the product's machine is the
press spiral, controller/insertion/spiral/): ``step(observation) -> Command``, pure and
non-blocking.

The phases, their rules and the transition table are documented in docs/ARCHITECTURE.md
("Insertion state machine", ``align``); the table itself is data (``definition.py``),
checked when the machine is built, and every transition the machine takes, and every
sub-stage it is in, must be in it. Each phase is a module of ``phases/`` (its sub-stages,
its state, its ``step``); this module dispatches to them and owns the transitions and the
checks common to them. Each tick, in this order: a device fault ends the run; the e-stop
button latches ESTOP; an operator in control takes over (TELEOP); the timeouts, the hard
limits and the slip policy are checked; then the current phase's ``step`` computes the
command and may move on. Every command names the rule (``Command.rule``) and the sub-stage
(``Command.stage``) that decided it.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from enum import Enum
from typing import TypeVar

import numpy as np
from scipy.spatial.transform import Rotation

from controller.insertion.commands import hold
from controller.insertion.definition import (
    AUTONOMOUS,
    IN_CONTACT,
    INSERTION,
    TERMINAL,
    Definition,
    check_definition,
)
from controller.insertion.grasp_estimate import GraspEstimate
from controller.insertion.interface import (
    Command,
    FailureReason,
    InHandEstimate,
    Observation,
    Phase,
    Transition,
)
from controller.insertion.machine_config import MachineConfig
from controller.insertion.motion import approach_rotation, rotation_error, tip_position
from controller.insertion.phases import (
    align,
    approach,
    backoff,
    feel,
    grasp,
    insert,
    overrides,
    release,
    retract,
    search,
)
from controller.insertion.phases.stage import PhaseState
from controller.insertion.search_path import SearchPattern
from controller.insertion.signals import TactileSignals
from controller.insertion.touch import TouchMemory
from core.spatial import clamp_norm, rotation_from_rpy, tilt_of_rotation, tool_z_in_base
from core.task_geometry import HolePose, PlugGeometry

_HOLDING = (Phase.APPROACH, *IN_CONTACT)
_TIMEOUT_KEYS = {
    Phase.GRASP: "grasp_s",
    Phase.APPROACH: "approach_s",
    Phase.FEEL: "feel_s",
    Phase.SEARCH: "search_s",
    Phase.ALIGN: "align_s",
    Phase.INSERT: "insert_s",
    Phase.BACKOFF: "backoff_s",
    Phase.RELEASE: "release_s",
    Phase.RETRACT: "retract_s",
}
Enter = Callable[[Observation, MachineConfig], PhaseState]
Step = Callable[["InsertionMachine", Observation, bool], Command]
_ENTER: dict[Phase, Enter] = {
    Phase.GRASP: grasp.enter,
    Phase.APPROACH: approach.enter,
    Phase.FEEL: feel.enter,
    Phase.SEARCH: search.enter,
    Phase.ALIGN: align.enter,
    Phase.INSERT: insert.enter,
    Phase.BACKOFF: backoff.enter,
    Phase.RELEASE: release.enter,
    Phase.RETRACT: retract.enter,
    Phase.TELEOP: overrides.enter_teleop,
    Phase.ESTOP: overrides.enter_estop,
    Phase.DONE: overrides.enter_terminal,
    Phase.FAILED: overrides.enter_terminal,
}
_STEP: dict[Phase, Step] = {
    Phase.GRASP: grasp.step,
    Phase.APPROACH: approach.step,
    Phase.FEEL: feel.step,
    Phase.SEARCH: search.step,
    Phase.ALIGN: align.step,
    Phase.INSERT: insert.step,
    Phase.BACKOFF: backoff.step,
    Phase.RELEASE: release.step,
    Phase.RETRACT: retract.step,
}
StateT = TypeVar("StateT")


@dataclass
class RunMemory:
    """What the machine carries from phase to phase during one run. ``preload_sigma``:
    SEARCH's axial load (noise units), which ALIGN and INSERT press with; ``retries``:
    back-offs and re-grasps so far; ``regrasp``: GRASP after a slip (lift and open first);
    ``keep_grasp``: GRASP on a resume with the plug held (settle and re-zero only);
    ``felt``: FEEL has run (once per run);
    ``released``: RELEASE was entered; ``search_s_m``: SEARCH's path length so far (m,
    kept when searching again); ``yaw_passes_from_m``: that length at SEARCH's first
    timeout (then each pass of the pattern is yawed); ``search_again``: the present
    BACKOFF ends in APPROACH (else in ALIGN)."""

    preload_sigma: float
    retries: int = 0
    regrasp: bool = False
    keep_grasp: bool = False
    felt: bool = False
    released: bool = False
    search_s_m: float = 0.0
    yaw_passes_from_m: float | None = None
    search_again: bool = False


class InsertionMachine:
    """The insertion machine for one run (implements ``interface.Machine``).

    ``config``: the task's ``machine:`` section; ``plug``: the grasped plug; ``hole``: the
    opening's nominal pose in B. ``definition``: the transition table and the sub-stages
    (the insertion table by default; checked here, DefinitionError if malformed).

    The phase modules (``phases/``) read ``config``, ``plug``, ``hole``, ``hole_xyz``,
    ``signals``, ``memory``, ``touch``, ``tick_s`` and ``grasp`` (FEEL's estimate of the
    plug in the hand, None before it), their own state (``state``), and act through
    ``fire``, ``go`` and ``fail``.
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
        self.memory = RunMemory(preload_sigma=config.approach.contact_sigma)
        self.touch = TouchMemory(plug, hole.z_m)
        self.hole_xyz = np.array([hole.x_m, hole.y_m, hole.z_m])  # the nominal opening, B (m)
        self.tick_s = 0.0  # time since the previous tick (s)
        self.grasp: GraspEstimate | None = None  # the plug in the hand, found by FEEL
        self._pattern = SearchPattern(
            config.search.pattern, config.search.pitch_m, config.search.uncertainty_xy_m
        )
        self._hole_yaw = Rotation.from_euler("z", hole.yaw_rad)
        self._approach_rot = approach_rotation(
            hole.yaw_rad, config.approach.tilt_rad, config.approach.tilt_axis
        )
        self._feel_rot = approach_rotation(hole.yaw_rad, 0.0, config.approach.tilt_axis)
        self._phase = definition.initial
        self._transitions: list[Transition] = []
        self._in_hand: list[InHandEstimate] = []  # FEEL's estimates (phases/feel.py)
        self._state_or_none: PhaseState | None = None  # None until the first step
        self._entered_t_s = 0.0  # when the present phase began (s)
        self._last_t_s: float | None = None
        self._autonomous_s = 0.0
        self._rule = ""  # the rule deciding this tick's command (Command.rule)
        self._decided: tuple[Phase, Enum] | None = None  # ... and its phase and sub-stage

    # -- the Machine protocol ------------------------------------------------------------

    @property
    def phase(self) -> Phase:
        return self._phase

    @property
    def stage(self) -> Enum:
        """The present phase's sub-stage (RuntimeError before the first step)."""
        return self._state.stage

    @property
    def transitions(self) -> tuple[Transition, ...]:
        return tuple(self._transitions)

    @property
    def in_hand_estimates(self) -> tuple[InHandEstimate, ...]:
        """FEEL's estimates of the plug's tilt in the width plane, in the order made."""
        return tuple(self._in_hand)

    def publish_in_hand(self, estimate: InHandEstimate) -> None:
        """Add ``estimate`` to ``in_hand_estimates`` (it commands nothing)."""
        self._in_hand.append(estimate)

    @property
    def retries(self) -> int:
        """Back-offs and re-grasps so far."""
        return self.memory.retries

    def step(self, observation: Observation) -> Command:
        """One tick: the command for ``observation`` (see the module doc), naming the rule
        and the sub-stage that decided it (``Command.rule``, ``Command.stage``)."""
        self._rule = ""
        self._decided = None
        command = self._decide(observation)
        phase, stage = self._decided or (self._phase, self._state.stage)
        if stage not in self.definition.stages.get(phase, ()):
            raise RuntimeError(
                f"sub-stage {phase.name}.{stage.name} is not in the machine's definition"
            )
        return dataclasses.replace(command, rule=self._rule, stage=f"{phase.value}.{stage.value}")

    def _decide(self, obs: Observation) -> Command:
        dt = 0.0 if self._last_t_s is None else max(obs.t_s - self._last_t_s, 0.0)
        self._last_t_s = obs.t_s
        self.tick_s = dt
        if self._state_or_none is None:
            self._enter(obs)
        if self._phase in AUTONOMOUS:
            self._autonomous_s += dt
        new = self.signals.update(obs.wrench)
        if self._phase in TERMINAL:
            self.fire("hold")
            return hold()
        if has_fault(obs):
            return self.fail(obs, FailureReason.DEVICE_FAULT)
        if obs.teleop.estop and self._phase is not Phase.ESTOP:
            self.go(obs, Phase.ESTOP, "estop")
        if self._phase is Phase.ESTOP:
            return overrides.estop(self, obs)
        if obs.teleop.in_control and self._phase in AUTONOMOUS:
            self.go(obs, Phase.TELEOP, "operator_takeover")
        if self._phase is Phase.TELEOP:
            return overrides.teleop(self, obs)
        failure = self._checks(obs)
        if failure is not None:
            return failure
        if self._phase in _HOLDING and self._slipped(obs, new):
            return self._on_slip(obs)
        return _STEP[self._phase](self, obs, new)

    # -- the phases' state -----------------------------------------------------------------

    @property
    def _state(self) -> PhaseState:
        """What the present phase has done so far (RuntimeError before the first step)."""
        if self._state_or_none is None:
            raise RuntimeError("the insertion machine has no phase state before its first step")
        return self._state_or_none

    def state(self, kind: type[StateT]) -> StateT:
        """The present phase's state, of type ``kind`` (RuntimeError if it is not)."""
        state = self._state
        if not isinstance(state, kind):
            raise RuntimeError(f"phase {self._phase.name} has no {kind.__name__}")
        return state

    def _enter(self, obs: Observation) -> None:
        """A fresh state for the present phase, entered at ``obs``."""
        self._state_or_none = _ENTER[self._phase](obs, self.config)
        self._entered_t_s = obs.t_s

    # -- transitions -----------------------------------------------------------------------

    def fire(self, rule: str) -> None:
        """Name the rule deciding this tick's command: ``phase.rule``, decided in the
        present sub-stage."""
        self._rule = f"{self._phase.value}.{rule}"
        self._decided = (self._phase, self._state.stage)

    def go(self, obs: Observation, target: Phase, guard: str, rule: str = "") -> None:
        """Move to ``target`` under ``guard`` (``rule``: which of the guard's rules fired)."""
        if not self.definition.allows(self._phase, target, guard):
            raise RuntimeError(
                f"transition {self._phase.name} -> {target.name} ({guard}) "
                "is not in the machine's definition"
            )
        self._transitions.append(Transition(obs.t_s, self._phase, target, guard, rule))
        self.fire(f"{guard}:{rule}" if rule else guard)
        self._phase = target
        self._enter(obs)
        if target is Phase.FEEL:
            self.memory.felt = True
        if guard == "hole_found":  # a new catch: no jam there yet
            self.touch.new_catch()
        if target is Phase.RELEASE:
            self.memory.released = True

    def fail(self, obs: Observation, reason: FailureReason) -> Command:
        """FAILED for ``reason``: hold still."""
        self.go(obs, Phase.FAILED, reason.value)
        return hold()

    # -- checks common to the autonomous phases ------------------------------------------

    def _checks(self, obs: Observation) -> Command | None:
        """FAILED for a timeout or an exceeded hard limit, else None."""
        timeouts = self.config.timeouts
        in_phase = obs.t_s - self._entered_t_s
        if self._autonomous_s > timeouts.total_s:
            return self.fail(obs, FailureReason.TIMEOUT)
        if in_phase > getattr(timeouts, _TIMEOUT_KEYS[self._phase]):
            if self._phase is Phase.ALIGN:  # a plug that would not align: lift, catch again
                return backoff.begin(self, obs, "align_timeout")
            if self._phase is Phase.SEARCH:  # no catch: search again, at other yaws
                if self.memory.yaw_passes_from_m is None:
                    self.memory.yaw_passes_from_m = self.memory.search_s_m
                return backoff.begin(self, obs, "search_timeout")
            return self.fail(obs, FailureReason.TIMEOUT)
        if self._phase in _HOLDING and self._limit_exceeded(obs):
            return self.fail(obs, FailureReason.LIMIT_EXCEEDED)
        return None

    def _limit_exceeded(self, obs: Observation) -> bool:
        limits = self.config.limits
        rotation = rotation_from_rpy(obs.arm.tcp.rpy_rad)
        if tilt_of_rotation(rotation) > limits.tilt_limit_rad:
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
            return self.fail(obs, FailureReason.SLIP)
        if self.memory.retries >= self.config.backoff.max_retries:
            return self.fail(obs, FailureReason.TOO_MANY_RETRIES)
        self.memory.retries += 1
        self.memory.regrasp = True
        self.memory.felt, self.grasp = False, None  # a new grasp: feel it again
        self.go(obs, Phase.GRASP, "slip_regrasp")
        return hold()

    # -- the search path, shared by APPROACH and SEARCH -------------------------------------

    def pattern_offset_b(self, s_m: float) -> np.ndarray:
        """The search pattern's offset from the nominal opening at path length ``s_m`` (m),
        as a vector in B (m; z zero)."""
        offset_uv = self._pattern.offset(s_m)
        return self._hole_yaw.apply([offset_uv[0], offset_uv[1], 0.0])

    def tip_shift_b(self, rotation: Rotation) -> np.ndarray:
        """Where the plug's tip is, less where the nominal grasp puts it, in B (m), for the
        TCP turned by ``rotation`` (T2B): FEEL's estimate (``grasp``), zero before it."""
        if self.grasp is None:
            return np.zeros(3)
        return self.grasp.tip_shift_b(rotation)

    def feel_first(self) -> bool:
        """FEEL is on (``feel.enabled``) and has not run on the present grasp."""
        return self.config.feel.enabled and not self.memory.felt

    def plug_axis_b(self, rotation: Rotation) -> np.ndarray:
        """The plug's axis (unit, toward its tip) in B for the TCP turned by ``rotation``
        (T2B): T z turned by FEEL's estimate, T z before it."""
        if self.grasp is None:
            return tool_z_in_base(rotation)
        return rotation.apply(self.grasp.tip_t / self.grasp.length_m)

    def search_rotation(self) -> Rotation:
        """Before FEEL (``feel_first``): the approach rotation without its tilt (T z straight
        down, so the tip's face can lie flat on the board). Then the approach rotation (T2B), turned
        about T y against FEEL's estimate of the
        plug's tilt in the hand (so the plug, not the arm, is as the approach has it), and
        about B's z by the present pass's yaw once SEARCH has run out of time
        (config.SearchSettings, ``retry_yaw_rad``)."""
        if self.feel_first():
            return self._feel_rot
        approach = self._approach_rot
        if self.grasp is not None:  # the plug upright, not the arm
            approach = approach * Rotation.from_euler("y", -self.grasp.tilt_rad)
        start, length = self.memory.yaw_passes_from_m, self._pattern.length_m
        if start is None or length <= 0.0:
            return approach
        passes = int((self.memory.search_s_m - start) // length)
        yaw = self.config.search.retry_yaw_rad * (1.0, -1.0, 0.0)[passes % 3]
        return Rotation.from_euler("z", yaw) * approach

    def hold_rotation(self, rotation: Rotation) -> np.ndarray:
        """Angular velocity in B (rad/s) servoing the TCP from ``rotation`` (T2B) to the
        search rotation."""
        settings = self.config.approach
        return clamp_norm(
            settings.pose_gain_1_s * rotation_error(rotation, self.search_rotation()),
            settings.rotate_speed_rad_s,
        )


def has_fault(obs: Observation) -> bool:
    """A device fault this tick: the loop's, the arm's error code or the gripper's."""
    return obs.fault is not None or obs.arm.error_code != 0 or obs.gripper.fault_code != 0
