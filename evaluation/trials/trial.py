"""One insertion trial: a run of the product's run path (``controller.run.run_task``),
scored against the simulator's truth.

``run_trial(spec)`` is the batch's trial function (evaluation/trials/spec.py); ``run(...)``
is what ``scripts/run_trial.py`` calls. The controller sees only what the devices give
(rendered tactile frames, the arm's and the gripper's status); the scene's truth goes to the
record (``truth.npz``) and to the outcome, and, for the ``oracle`` controller only, in place
of the estimate (evaluation/trials/oracle.py). On the real backend the same run path runs
on the robot, and the outcome is the machine's (no truth).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from controller.insertion import Phase
from controller.loop import LoopResult
from controller.run import RunOutcome, Task, load_task, run_task
from core.atomic_files import atomic_file
from evaluation.common.cli_support import Terminated
from evaluation.trials.oracle import TRIAL_CONTROLLERS
from evaluation.trials.result import TrialResult
from evaluation.trials.spec import TrialSpec
from evaluation.trials.trial_chart import write_trial_chart


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
    """The batch's trial function: one simulated trial, as fast as possible; with
    ``spec.out_dir``, its record and its chart (``summary.png``) go there. A signal that
    stopped the trial's loop (after its safe stop) stops the batch too, as KeyboardInterrupt
    (SIGINT) or Terminated (SIGTERM): an interrupted trial is not a failed one."""
    task = load_task(spec.task, spec.overrides)
    outcome = run(task, spec.controller, spec.seed, out_dir=spec.out_dir)
    raise_if_interrupted(outcome)
    if spec.out_dir is not None:
        write_trial_chart(spec.out_dir, outcome.result)
    return outcome.result


def raise_if_interrupted(outcome: TrialOutcome) -> None:
    """KeyboardInterrupt (SIGINT) or Terminated (SIGTERM) if a signal stopped the trial's
    loop (after its safe stop), so a tool running several trials stops with it."""
    if outcome.loop.reason == "signal":
        raise KeyboardInterrupt if outcome.loop.message == "SIGINT" else Terminated()


def run(
    task: Task, controller: str, seed: int, *, out_dir: Path | None = None, **run_options: Any
) -> TrialOutcome:
    """Run one trial of ``task`` with ``controller`` (see the module doc): the product's
    ``run_task`` with the trial tools' controllers (the oracle too) and the same
    ``run_options`` (``backend``, ``realtime``, ``observers``, ``prepare``), scored against
    the simulated world's truth; ``out_dir``: the run's record, with ``truth.npz`` and the
    trial's summary in ``trial.json``."""
    ran = run_task(
        task, controller, seed, out_dir=out_dir, controllers=TRIAL_CONTROLLERS, **run_options
    )
    world = ran.devices.world
    if world is None:
        result = _result_on_hardware(task, controller, seed, ran)
        truth = None
    else:
        world.sync()
        truth = world.truth.arrays()
        result = _result(task, controller, seed, ran, truth)
        if out_dir is not None:
            write_truth(out_dir, truth, dataclasses.asdict(world.truth.hole))
    if ran.recorder is not None:
        ran.recorder.write_summary(_summary(task, controller, seed, result, ran))
    return TrialOutcome(result, ran.loop, ran.transitions, truth)


def write_truth(folder: Path, truth: dict[str, np.ndarray], hole: dict[str, float]) -> None:
    """``folder/truth.npz``: the ground truth arrays and the true hole pose, atomically."""
    with atomic_file(folder / "truth.npz") as staging, staging.open("wb") as handle:
        np.savez_compressed(handle, **truth, **{f"hole_{k}": v for k, v in hole.items()})


def _result(task, controller, seed, ran: RunOutcome, truth) -> TrialResult:
    config = task.config
    depth = truth["depth_m"]
    t = truth["t_s"]
    required = config.machine.insert.depth_m
    reached = np.flatnonzero(depth >= required)
    started = ran.loop.stats.first_tick_s  # after the devices' start-up (activation)
    time_to_insert = float(t[reached[0]] - started) if reached.size else None
    done = ran.machine.phase is Phase.DONE
    success = done and reached.size > 0
    failure = None
    if not success:
        failed = [tr for tr in ran.transitions if tr.target is Phase.FAILED]
        if failed:
            failure = failed[-1].reason
        elif done:
            failure = "done without reaching the depth"
        else:
            failure = f"loop ended: {ran.loop.reason}"
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
        wall_time_s=ran.wall_s,
    )


def _result_on_hardware(task, controller, seed, ran: RunOutcome) -> TrialResult:
    """The machine's own outcome (no truth on hardware; ``seed`` is recorded only)."""
    success = ran.machine.phase is Phase.DONE
    failed = [tr.reason for tr in ran.transitions if tr.target is Phase.FAILED]
    return TrialResult(
        task=task.config.task,
        controller=controller,
        seed=seed,
        success=success,
        status="inserted" if success else "failed",
        failure_reason=None if success else (failed[-1] if failed else ran.loop.reason),
        time_to_insert_s=None,
        duration_s=ran.wall_s,
        max_true_force_n=float("nan"),
        force_limit_n=task.config.force_limit_n,
        wall_time_s=ran.wall_s,
    )


def _summary(task, controller, seed, result, ran: RunOutcome) -> dict[str, Any]:
    loop = ran.loop
    return {
        "task": task.config.task,
        "task_file": str(task.path),
        "overrides": list(task.overrides),
        "controller": controller,
        "seed": seed,
        "result": result.as_row(),
        "loop": {"reason": loop.reason, "message": loop.message, **dataclasses.asdict(loop.stats)},
        "transitions": [
            {"t_s": tr.t_s, "from": tr.source.value, "to": tr.target.value, "reason": tr.reason}
            for tr in ran.transitions
        ],
        "config": task.raw,
    }
