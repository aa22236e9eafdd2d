"""One insertion trial: a run of the run path (``run_task``) with its episode, its record's
summary and its outcome (``TrialResult``).

On the robot the outcome is the machine's own (no truth). In simulation the outcome is
scored against the simulator's truth by a ``TruthScoring`` that the caller passes in
(evaluation/trials/trial.py: the product never reads the truth, nor imports the simulator).
"""

from __future__ import annotations

import dataclasses
import json
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from controller.episode.session import EPISODE_FILE, EpisodeOptions, EpisodeRecording
from controller.insertion import Phase
from controller.loop import LoopResult
from controller.run.controllers import CONTROLLERS, Controller
from controller.run.result import TrialResult
from controller.run.runner import RunOutcome, run_task
from controller.run.task import Task

MAX_SEED = 2**32 - 1
"""The largest seed of a trial (the simulated scene's draws take a 32-bit seed)."""


@dataclass(frozen=True)
class TrialOutcome:
    """A finished trial: its ``result``, the loop's, the machine's transitions and, in
    simulation, the ground truth arrays (None on hardware)."""

    result: TrialResult
    loop: LoopResult
    transitions: tuple
    truth: dict[str, np.ndarray] | None


class TruthScoring(Protocol):
    """How a simulated trial is scored against the simulator's truth."""

    def run_options(
        self, recording: EpisodeRecording | None, run_options: dict[str, Any]
    ) -> dict[str, Any]:
        """``run_task``'s options for a simulated run (e.g. an observer that logs the truth
        into ``recording``)."""
        ...

    def score(
        self, task: Task, controller: str, seed: int, ran: RunOutcome, out_dir: Path | None
    ) -> tuple[TrialResult, dict[str, np.ndarray]]:
        """The result of the finished simulated run ``ran`` and its truth arrays (written to
        ``out_dir`` with the record, if given)."""
        ...


def run(
    task: Task,
    controller: str,
    seed: int,
    *,
    out_dir: Path | None = None,
    episode: EpisodeOptions | None = None,
    controllers: Mapping[str, Controller] = CONTROLLERS,
    scoring: TruthScoring | None = None,
    **run_options: Any,
) -> TrialOutcome:
    """Run one trial of ``task`` with ``controller`` (a name of ``controllers``) and
    ``run_task``'s ``run_options`` (``backend``, ``realtime``, ``observers``, ``prepare``);
    ``out_dir``: the run's record, with the trial's summary in ``trial.json``; ``episode``:
    also write ``out_dir/episode.mcap`` (docs/EPISODES.md) with these options and the trial's
    result in its outcome; ``scoring``: how a simulated run is scored (required for
    ``backend: sim``)."""
    if episode is None:
        return _run(task, controller, seed, out_dir, None, controllers, scoring, run_options)
    if out_dir is None:
        raise ValueError("episode: a trial writes its episode into out_dir; give one")
    out_dir.mkdir(parents=True, exist_ok=True)
    recording = EpisodeRecording(
        out_dir / EPISODE_FILE,
        task.raw,
        task=task.config.task,
        task_file=task.path,
        overrides=task.overrides,
        seed=seed,
        controller=controller,
        backend=run_options.get("backend", "sim"),
        options=episode,
        calibration=task.calibration,
    )
    try:
        outcome = _run(task, controller, seed, out_dir, recording, controllers, scoring,
                       run_options)  # fmt: skip
    except BaseException as error:
        recording.close({"error": f"{type(error).__name__}: {error}"})
        raise
    recording.close(episode_outcome(outcome))
    return outcome


def episode_outcome(outcome: TrialOutcome) -> dict[str, str]:
    """The episode's ``outcome`` metadata of a finished trial."""
    loop = outcome.loop
    return {
        "reason": loop.reason,
        "message": loop.message,
        "phase": loop.phase.value,
        "result": json.dumps(outcome.result.as_row(), default=str),
        "error": "",
    }


def _run(
    task: Task,
    controller: str,
    seed: int,
    out_dir: Path | None,
    recording: EpisodeRecording | None,
    controllers: Mapping[str, Controller],
    scoring: TruthScoring | None,
    run_options: dict[str, Any],
) -> TrialOutcome:
    if scoring is not None and run_options.get("backend", "sim") == "sim":
        run_options = scoring.run_options(recording, run_options)
    ran = run_task(
        task,
        controller,
        seed,
        out_dir=out_dir,
        controllers=controllers,
        episode=recording,
        **run_options,
    )
    truth = None
    if ran.devices.world is None:
        result = result_on_hardware(task, controller, seed, ran)
    elif scoring is None:
        raise ValueError("a simulated trial is scored against the truth: give scoring")
    else:
        result, truth = scoring.score(task, controller, seed, ran, out_dir)
    if ran.recorder is not None:
        ran.recorder.write_summary(_summary(task, controller, seed, result, ran))
    return TrialOutcome(result, ran.loop, ran.transitions, truth)


def result_on_hardware(task: Task, controller: str, seed: int, ran: RunOutcome) -> TrialResult:
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
        max_wrist_force_n=float("nan"),
        force_limit_n=task.config.force_limit_n,
        wall_time_s=ran.wall_s,
        max_contact_force_n=float("nan"),
        p99_contact_force_n=float("nan"),
        contact_force_limit_n=task.config.contact_force_limit_n,
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
