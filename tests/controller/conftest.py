"""Shared pieces of the control-loop tests: sim twins on a ManualClock, scripted machines and
a scripted estimator (the real one is exercised in one test; the rest stays fast)."""

from __future__ import annotations

from collections.abc import Callable
from contextlib import contextmanager

import pytest

from controller.insertion.interface import (
    Command,
    FailureReason,
    Observation,
    Phase,
    Transition,
)
from controller.tactile.wrench import WrenchEstimate
from core.clock import ManualClock
from core.config import CONFIG_ROOT as CONFIGS
from core.devices import Devices
from drivers import registry

START_S = 5.0


class ScriptedMachine:
    """A machine for the loop's tests: ``script(observation, k) -> Command`` each step;
    DONE after ``done_after`` steps (None: never); FAILED on a fault observation."""

    def __init__(
        self,
        script: Callable[[Observation, int], Command] | None = None,
        done_after: int | None = None,
    ) -> None:
        self.script = script if script is not None else (lambda obs, k: Command())
        self.done_after = done_after
        self.steps = 0
        self.observations: list[Observation] = []
        self._phase = Phase.APPROACH
        self._transitions: list[Transition] = []

    @property
    def phase(self) -> Phase:
        return self._phase

    @property
    def transitions(self) -> tuple[Transition, ...]:
        return tuple(self._transitions)

    def step(self, observation: Observation) -> Command:
        self.observations.append(observation)
        if observation.fault is not None:
            self._go(observation.t_s, Phase.FAILED, FailureReason.DEVICE_FAULT.value)
            return Command()
        command = self.script(observation, self.steps)
        self.steps += 1
        if self.done_after is not None and self.steps >= self.done_after:
            self._go(observation.t_s, Phase.DONE, "scripted end")
        return command

    def _go(self, t_s: float, target: Phase, reason: str) -> None:
        self._transitions.append(Transition(t_s, self._phase, target, reason))
        self._phase = target


class ScriptedEstimator:
    """A ``WrenchSource`` standing for ``TactileEstimator``: returns ``wrench(t_s)`` for each
    pushed frame and records pushes, open-gel captures and re-zero requests."""

    def __init__(self, wrench: Callable[[float], WrenchEstimate] | None = None) -> None:
        self.wrench = wrench if wrench is not None else quiet
        self.pushed: list[float] = []
        self.opened: list[int | None] = []
        self.rezeroed: list[int | None] = []

    def push(self, frame, t_s: float) -> WrenchEstimate:
        self.pushed.append(t_s)
        return self.wrench(t_s)

    def capture_open(self, n_frames: int | None = None) -> None:
        self.opened.append(n_frames)

    def rezero(self, n_frames: int | None = None) -> None:
        self.rezeroed.append(n_frames)


def quiet(t_s: float) -> WrenchEstimate:
    """A calibrated estimate with nothing in contact."""
    return WrenchEstimate.zero(t_s, zeroing=False, calibrated=True)


@pytest.fixture
def clock() -> ManualClock:
    return ManualClock(START_S)


@contextmanager
def sim_devices(clock, activate: bool = True):
    """Connected sim twins (arm, gripper, tactile camera, gamepad) on ``clock``, the
    gripper activated if ``activate`` (1 s on the clock)."""

    def load(path: str):
        return registry.load_device(CONFIGS / path, backend="sim", clock=clock)

    built = Devices(
        arm=load("robot/xarm6.yaml"),
        gripper=load("gripper/hande.yaml"),
        tactile=load("sensors/gelsight_mini_camera.yaml"),
        gamepad=load("gamepad/xbox.yaml"),
    )
    with built.arm, built.gripper, built.tactile, built.gamepad:
        if activate:
            built.gripper.activate()
        yield built


@pytest.fixture
def devices(clock):
    """The sim twins on the test's ManualClock."""
    with sim_devices(clock) as built:
        yield built
