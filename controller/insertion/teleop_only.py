"""The teleoperated alignment demo's machine (``scripts/teleop_demo.py`` without
``--autonomy``): grasp, then the operator drives; no autonomous motion after the grasp.

Phases (``TELEOP_ONLY``, checked like the insertion table):

* GRASP: the insertion machine's own grasp (capture the open gel, close, settle, re-zero,
  baseline; ``InsertionMachine`` runs it and nothing after it). The pad is not obeyed yet:
  the tactile reference is taken with the arm still.
* TELEOP (``grasped_and_zeroed``): the operator's twist and gripper buttons, through the
  same ``operator_command`` as the insertion machine's TELEOP, then the loop's limits and
  watchdog as every command; a zero twist (hold still) while no stick is deflected, the
  deadman is released, or the pad is unplugged (the watchdog trips on the latter while the
  operator holds control). ``hand_back`` ends the demo (DONE): there is no autonomy to hand
  back to.
* ESTOP: the e-stop button latches it from GRASP or TELEOP; the arm holds until the button
  is released **and** acknowledged (``estop_ack``), then TELEOP (GRASP if the grasp was not
  finished).
* ``request_rezero`` (the live view's key): the next TELEOP tick re-zeroes the tactile
  reference, holding still.
* FAILED: a device fault (``device_fault``) in any phase, the grasp's ``timeout``.
"""

from __future__ import annotations

import dataclasses

from controller.insertion.commands import operator_command
from controller.insertion.definition import (
    INSERTION,
    TERMINAL,
    Definition,
    Edge,
    check_definition,
)
from controller.insertion.interface import (
    Command,
    FailureReason,
    InHandEstimate,
    Observation,
    Phase,
    TeleopInput,
    Transition,
)
from controller.insertion.machine import InsertionMachine, has_fault
from controller.insertion.machine_config import MachineConfig
from core.devices import Twist
from core.task_geometry import HolePose, PlugGeometry

_F = FailureReason
_PHASES = (Phase.GRASP, Phase.TELEOP, Phase.ESTOP, Phase.DONE, Phase.FAILED)
TELEOP_ONLY = Definition(
    phases=_PHASES,
    initial=Phase.GRASP,
    terminal=TERMINAL,
    edges=(
        Edge(Phase.GRASP, Phase.TELEOP, "grasped_and_zeroed"),
        Edge(Phase.GRASP, Phase.FAILED, _F.TIMEOUT.value),
        Edge(Phase.TELEOP, Phase.DONE, "hand_back"),
        *(Edge(p, Phase.ESTOP, "estop") for p in (Phase.GRASP, Phase.TELEOP)),
        *(Edge(Phase.ESTOP, p, "estop_acknowledged") for p in (Phase.GRASP, Phase.TELEOP)),
        *(
            Edge(p, Phase.FAILED, _F.DEVICE_FAULT.value)
            for p in (Phase.GRASP, Phase.TELEOP, Phase.ESTOP)
        ),
    ),  # fmt: skip
    stages={phase: INSERTION.stages[phase] for phase in _PHASES},
)


class TeleopOnlyMachine:
    """The demo's machine (implements ``interface.Machine``; see the module doc).
    ``config``, ``plug``, ``hole``: as ``InsertionMachine``'s (its grasp uses them)."""

    def __init__(self, config: MachineConfig, plug: PlugGeometry, hole: HolePose) -> None:
        check_definition(TELEOP_ONLY)
        self.config = config
        self._grasp = InsertionMachine(config, plug, hole)
        self._phase = TELEOP_ONLY.initial
        self._transitions: list[Transition] = []
        self._grasped = False
        self._rezero_wanted = False

    @property
    def phase(self) -> Phase:
        return self._phase

    @property
    def transitions(self) -> tuple[Transition, ...]:
        return tuple(self._transitions)

    @property
    def in_hand_estimates(self) -> tuple[InHandEstimate, ...]:
        """None: the operator inserts; nothing is felt."""
        return ()

    def step(self, observation: Observation) -> Command:
        obs = observation
        hold = Command(twist=Twist())
        if self._phase in TERMINAL:
            return hold
        if has_fault(obs):
            self._go(obs, Phase.FAILED, _F.DEVICE_FAULT.value)
            return hold
        teleop = obs.teleop
        if teleop.estop and self._phase is not Phase.ESTOP:
            self._go(obs, Phase.ESTOP, "estop")
        if self._phase is Phase.ESTOP:
            if not teleop.estop and teleop.estop_ack:
                resumed = Phase.TELEOP if self._grasped else Phase.GRASP
                self._go(obs, resumed, "estop_acknowledged")
            return hold
        if self._phase is Phase.GRASP:
            return self._step_grasp(obs)
        if teleop.hand_back:
            self._go(obs, Phase.DONE, "hand_back")
            return hold
        if self._rezero_wanted:
            self._rezero_wanted = False
            return Command(twist=Twist(), rezero_tactile=True)
        limits = self.config.limits
        return operator_command(
            teleop, self.config.gripper, limits.max_command_speed_m_s,
            limits.max_command_angular_speed_rad_s,
        )  # fmt: skip

    def request_rezero(self) -> None:
        """Re-zero the tactile reference at the next TELEOP tick (the view's key; safe to
        call from another thread: one flag, read and cleared by ``step``). The arm holds
        still for that tick."""
        self._rezero_wanted = True

    def _step_grasp(self, obs: Observation) -> Command:
        """The insertion machine's grasp, the pad hidden from it (it would take over)."""
        neutral = TeleopInput(connected=obs.teleop.connected)
        command = self._grasp.step(dataclasses.replace(obs, teleop=neutral))
        if self._grasp.phase is Phase.APPROACH:
            self._grasped = True
            self._go(obs, Phase.TELEOP, "grasped_and_zeroed")
            return Command(twist=Twist())
        if self._grasp.phase is Phase.FAILED:
            self._go(obs, Phase.FAILED, self._grasp.transitions[-1].reason)
            return Command(twist=Twist())
        return command

    def _go(self, obs: Observation, target: Phase, guard: str) -> None:
        if not TELEOP_ONLY.allows(self._phase, target, guard):
            raise RuntimeError(f"transition {self._phase.name} -> {target.name} ({guard}) "
                               "is not in the teleop demo's definition")  # fmt: skip
        self._transitions.append(Transition(obs.t_s, self._phase, target, guard))
        self._phase = target
