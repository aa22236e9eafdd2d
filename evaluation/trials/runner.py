"""One insertion trial: the task's machine, control loop and estimator on the simulated
scene (or on the real devices), with the ground truth recorded beside it.

``run_trial(spec)`` is the batch's trial function (evaluation/trials/spec.py);
``run(...)`` is what ``scripts/run_trial.py`` calls. The controller sees only what the
devices give (rendered tactile frames, the arm's and the gripper's status); the scene's
truth goes to the record and to the outcome, and, for the ``oracle`` controller only, in
place of the estimate (evaluation/trials/torque_sources.py).
"""

from __future__ import annotations

import dataclasses
import time
from collections.abc import Sequence
from contextlib import ExitStack
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from controller.insertion import InsertionMachine, Machine, Phase
from controller.insertion.blind import BlindMachine
from controller.loop import ControlLoop, Devices, LoopResult
from controller.tactile import estimator_for_sensor
from core.clock import MonotonicClock
from core.config import ConfigError
from drivers.registry import load_device, load_device_config
from drivers.sim.scenes.insertion import SimDevices, build_insertion_sim
from drivers.sim.twins.gamepad import PadEvent
from evaluation.common.cli_support import Terminated
from evaluation.trials.record import TrialRecorder
from evaluation.trials.result import TrialResult
from evaluation.trials.spec import TrialSpec
from evaluation.trials.task import Task, TaskConfig, load_task
from evaluation.trials.torque_sources import BaselineTorques, TrueWrench

DEVICE_KINDS = ("arm", "gripper", "tactile", "gamepad")
LOOP_MARGIN_S = 5.0  # the loop's own cap beyond the machine's total timeout, s


@dataclass(frozen=True)
class TrialOutcome:
    """A finished trial: its ``result``, the loop's, the machine's transitions and, in
    simulation, the ground truth arrays (None on hardware)."""

    result: TrialResult
    loop: LoopResult
    transitions: tuple
    truth: dict[str, np.ndarray] | None


def check_spec(spec: TrialSpec) -> None:
    """ConfigError (one line) if ``spec``'s task or overrides are wrong (the batch's check)."""
    load_task(spec.task, spec.overrides)


def run_trial(spec: TrialSpec) -> TrialResult:
    """The batch's trial function: one simulated trial, as fast as possible. A signal that
    stopped the trial's loop (after its safe stop) stops the batch too, as KeyboardInterrupt
    (SIGINT) or Terminated (SIGTERM): an interrupted trial is not a failed one."""
    task = load_task(spec.task, spec.overrides)
    outcome = run(task, spec.controller, spec.seed, out_dir=spec.out_dir)
    raise_if_interrupted(outcome)
    return outcome.result


def raise_if_interrupted(outcome: TrialOutcome) -> None:
    """KeyboardInterrupt (SIGINT) or Terminated (SIGTERM) if a signal stopped the trial's
    loop (after its safe stop), so a tool running several trials stops with it."""
    if outcome.loop.reason == "signal":
        raise KeyboardInterrupt if outcome.loop.message == "SIGINT" else Terminated()


def _sim_device_configs(config: TaskConfig) -> SimDevices:
    configs = {
        kind: load_device_config(path, backend="sim", kind=kind).config
        for kind in DEVICE_KINDS
        if (path := config.devices.path(kind)) is not None
    }
    return SimDevices(**configs)


def run(
    task: Task,
    controller: str,
    seed: int,
    *,
    backend: str = "sim",
    realtime: bool = False,
    out_dir: Path | None = None,
    pad_script: Sequence[PadEvent] = (),
) -> TrialOutcome:
    """Run one trial of ``task`` with ``controller`` on ``backend`` (see the module doc).
    ``pad_script``: in simulation, events the simulated gamepad plays from the trial's
    start (a scripted operator; the task's devices must name a gamepad)."""
    if backend == "real":
        if controller == "oracle":
            raise ConfigError("controller 'oracle' reads the simulator's truth: sim only")
        return _run_real(task, controller, seed, out_dir)
    config = task.config
    devices = _sim_device_configs(config)
    sim = build_insertion_sim(config.scene, config.plug, config.hole, devices, seed, realtime)
    if pad_script:
        if sim.gamepad is None:
            raise ConfigError("pad_script: the task's devices name no gamepad")
        sim.gamepad.play(pad_script)
    estimator = estimator_for_sensor(devices.tactile.model, config.estimator)
    source = _torque_source(controller, estimator, sim)
    machine = _machine(config, controller)
    recorder = TrialRecorder(out_dir, machine) if out_dir is not None else None
    began = time.perf_counter()
    try:
        loop_result = _run_loop(task, machine, source, sim, sim.clock, recorder)
    finally:
        if recorder is not None:
            recorder.close()
    wall_s = time.perf_counter() - began
    sim.sync()
    truth = sim.truth.arrays()
    result = _result(task, controller, seed, machine, loop_result, truth, wall_s)
    if recorder is not None:
        hole = dataclasses.asdict(sim.truth.hole)
        recorder.write_truth(truth, hole)
        recorder.write_summary(_summary(task, controller, seed, result, loop_result, machine))
    return TrialOutcome(result, loop_result, machine.transitions, truth)


def _machine(config: TaskConfig, controller: str) -> Machine:
    """The tactile machine, or the blind baseline."""
    if controller == "blind":
        return BlindMachine(config.blind, config.plug, config.hole)
    return InsertionMachine(config.machine, config.plug, config.hole)


def _torque_source(controller: str, estimator, sim) -> Any:
    if controller in ("dipole", "blind"):  # blind: estimated, recorded, never used
        return estimator
    if controller == "fingervision":
        return BaselineTorques(estimator)
    if controller == "oracle":
        def newest_true_wrench() -> np.ndarray:
            sim.sync()
            rows = sim.truth.arrays()["gel_wrench_s"]
            return rows[-1] if len(rows) else np.zeros(6)

        return TrueWrench(estimator, newest_true_wrench)
    raise ConfigError(f"controller {controller!r}: expected dipole, fingervision, oracle or blind")


def _run_loop(task: Task, machine, source, sim, clock, recorder) -> LoopResult:
    config = task.config
    with ExitStack() as stack:
        for device in (sim.arm, sim.gripper, sim.tactile, sim.gamepad):
            if device is not None:
                stack.enter_context(device)
        sim.gripper.activate()
        devices = Devices(sim.arm, sim.gripper, sim.tactile, sim.gamepad)
        loop = ControlLoop(
            machine,
            devices,
            source,
            clock,
            config.loop,
            config.limits,
            config.teleop,
            observer=recorder,
        )
        return loop.run(max_duration_s=config.machine.timeouts.total_s + LOOP_MARGIN_S)


def _result(task, controller, seed, machine, loop_result, truth, wall_s) -> TrialResult:
    config = task.config
    depth = truth["depth_m"]
    t = truth["t_s"]
    required = config.machine.insert.depth_m
    reached = np.flatnonzero(depth >= required)
    started = loop_result.stats.first_tick_s  # after the devices' start-up (activation)
    time_to_insert = float(t[reached[0]] - started) if reached.size else None
    done = machine.phase is Phase.DONE
    success = done and reached.size > 0
    failure = None
    if not success:
        failed = [tr for tr in machine.transitions if tr.target is Phase.FAILED]
        if failed:
            failure = failed[-1].reason
        elif done:
            failure = "done without reaching the depth"
        else:
            failure = f"loop ended: {loop_result.reason}"
    wrist = truth["wrist_wrench_t"][:, :3]
    max_force = float(np.linalg.norm(wrist, axis=1).max()) if len(wrist) else 0.0
    return TrialResult(
        task=config.task,
        controller=controller,
        seed=seed,
        success=success,
        status="inserted" if success else "failed",
        failure_reason=failure,
        time_to_insert_s=time_to_insert if success else None,
        duration_s=float(t[-1] - t[0]) if len(t) else 0.0,
        max_true_force_n=max_force,
        force_limit_n=config.force_limit_n,
        wall_time_s=wall_s,
    )


def _summary(task, controller, seed, result, loop_result, machine) -> dict[str, Any]:
    return {
        "task": task.config.task,
        "task_file": str(task.path),
        "overrides": list(task.overrides),
        "controller": controller,
        "seed": seed,
        "result": result.as_row(),
        "loop": {"reason": loop_result.reason, "message": loop_result.message,
                 **dataclasses.asdict(loop_result.stats)},
        "transitions": [
            {"t_s": tr.t_s, "from": tr.source.value, "to": tr.target.value, "reason": tr.reason}
            for tr in machine.transitions
        ],
        "config": task.raw,
    }


def _run_real(task: Task, controller: str, seed: int, out_dir: Path | None) -> TrialOutcome:
    """The same machine and loop on the real devices (real time; no truth: the outcome is
    the machine's). ``seed`` is recorded only."""
    config = task.config
    clock = MonotonicClock()
    with ExitStack() as stack:
        built = {
            kind: stack.enter_context(load_device(path, backend="real", kind=kind, clock=clock))
            for kind in DEVICE_KINDS
            if (path := config.devices.path(kind)) is not None
        }
        tactile_model = load_device_config(config.devices.path("tactile"), backend="real").config
        estimator = estimator_for_sensor(tactile_model.model, config.estimator)
        source = BaselineTorques(estimator) if controller == "fingervision" else estimator
        machine = _machine(config, controller)
        recorder = TrialRecorder(out_dir, machine) if out_dir is not None else None
        if recorder is not None:
            stack.callback(recorder.close)
        built["gripper"].activate()
        devices = Devices(built["arm"], built["gripper"], built["tactile"], built.get("gamepad"))
        began = time.perf_counter()
        loop = ControlLoop(
            machine, devices, source, clock, config.loop, config.limits, config.teleop,
            observer=recorder,
        )
        loop_result = loop.run(max_duration_s=config.machine.timeouts.total_s + LOOP_MARGIN_S)
        wall_s = time.perf_counter() - began
    success = machine.phase is Phase.DONE
    failed = [tr.reason for tr in machine.transitions if tr.target is Phase.FAILED]
    result = TrialResult(
        task=config.task,
        controller=controller,
        seed=seed,
        success=success,
        status="inserted" if success else "failed",
        failure_reason=None if success else (failed[-1] if failed else loop_result.reason),
        time_to_insert_s=None,
        duration_s=wall_s,
        max_true_force_n=float("nan"),
        force_limit_n=config.force_limit_n,
        wall_time_s=wall_s,
    )
    if recorder is not None:
        recorder.write_summary(_summary(task, controller, seed, result, loop_result, machine))
    return TrialOutcome(result, loop_result, machine.transitions, None)

