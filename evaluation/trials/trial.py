"""One simulated insertion trial: a run of the product's trial (``controller.run.insertion_trial``),
scored against the simulator's truth.

``run_trial(spec)`` is the batch's trial function (evaluation/trials/spec.py); ``run(...)``
is what ``tactile trial`` calls in simulation. The controller sees only what the devices give
(rendered tactile frames, the arm's and the gripper's status); the scene's truth goes to the
record (``truth.npz``), to the episode (``/sim/`` topics) and to the outcome, and, for the
``oracle`` controller only, in place of the estimate (evaluation/trials/oracle.py). With
``backend="real"`` the same run runs on the robot, and the outcome is the machine's (no
truth).
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path
from typing import Any

import numpy as np

from controller.cli.support import Terminated
from controller.episode.session import EpisodeOptions, EpisodeRecording
from controller.insertion import Phase
from controller.replay.trial_chart import write_trial_chart
from controller.run import RunOutcome, Task, load_task
from controller.run import insertion_trial as product_trial
from controller.run.insertion_trial import TrialOutcome
from controller.run.result import TrialResult
from core.atomic_files import atomic_file
from evaluation.trials.entry_torque import entry_torques
from evaluation.trials.oracle import TRIAL_CONTROLLERS
from evaluation.trials.spec import TrialSpec


def check_spec(spec: TrialSpec) -> None:
    """ConfigError (one line) if ``spec``'s task or overrides are wrong (the batch's check)."""
    load_task(spec.task, spec.overrides)


def run_trial(spec: TrialSpec) -> TrialResult:
    """The batch's trial function: one simulated trial, as fast as possible; with
    ``spec.out_dir``, its record and its chart (``summary.png``) go there. A signal that
    stopped the trial's loop (after its safe stop) stops the batch too, as KeyboardInterrupt
    (SIGINT) or Terminated (SIGTERM): an interrupted trial is not a failed one."""
    task = load_task(spec.task, spec.overrides)
    episode = EpisodeOptions() if spec.episode else None
    outcome = run(task, spec.controller, spec.seed, out_dir=spec.out_dir, episode=episode)
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
    task: Task,
    controller: str,
    seed: int,
    *,
    out_dir: Path | None = None,
    episode: EpisodeOptions | None = None,
    **run_options: Any,
) -> TrialOutcome:
    """Run one trial of ``task`` with ``controller`` (see the module doc): the product's trial
    (``controller.run.insertion_trial.run``) with the trial tools' controllers (the oracle too)
    and the same ``run_options`` (``backend``, ``realtime``, ``observers``, ``prepare``), scored
    against the simulated world's truth; ``out_dir``: the run's record, with ``truth.npz``
    and the trial's summary in ``trial.json``; ``episode``: also write
    ``out_dir/episode.mcap`` (docs/EPISODES.md) with these options, the truth on ``/sim/``
    topics in simulation and the trial's result in its outcome."""
    return product_trial.run(
        task,
        controller,
        seed,
        out_dir=out_dir,
        episode=episode,
        controllers=TRIAL_CONTROLLERS,
        scoring=SimTruthScoring(),
        **run_options,
    )


class SimTruthScoring:
    """A simulated trial scored against the world's truth (``controller.run.insertion_trial``'s
    ``TruthScoring``): with an episode, the truth goes to its ``/sim/`` topics each tick."""

    def __init__(self) -> None:
        self.truth_logger: Any = None

    def run_options(
        self, recording: EpisodeRecording | None, run_options: dict[str, Any]
    ) -> dict[str, Any]:
        if recording is None:
            return run_options
        # imported here: the truth's columns come from the simulator, which a real run
        # never loads
        from evaluation.trials.episode_truth import SimTruthLogger

        truth_logger = self.truth_logger = SimTruthLogger(recording)
        prepare = run_options.pop("prepare", None)

        def prepare_and_attach(device_set: Any) -> None:
            truth_logger.attach(device_set.world)
            if prepare is not None:
                prepare(device_set)

        return {
            **run_options,
            "prepare": prepare_and_attach,
            "observers": [*run_options.get("observers", ()), truth_logger],
        }

    def score(
        self, task: Task, controller: str, seed: int, ran: RunOutcome, out_dir: Path | None
    ) -> tuple[TrialResult, dict[str, np.ndarray]]:
        world = ran.devices.world
        world.sync()
        truth = world.truth.arrays()
        result = _result(task, controller, seed, ran, truth)
        if self.truth_logger is not None:
            self.truth_logger.drain()
        if out_dir is not None:
            write_truth(out_dir, truth, dataclasses.asdict(world.truth.hole))
        return result, truth


def write_truth(folder: Path, truth: dict[str, np.ndarray], hole: dict[str, float]) -> None:
    """``folder/truth.npz``: the ground truth arrays and the true hole pose, atomically."""
    with atomic_file(folder / "truth.npz") as staging, staging.open("wb") as handle:
        np.savez_compressed(handle, **truth, **{f"hole_{k}": v for k, v in hole.items()})


INSERTION_FORCE_EXCEEDED = "insertion_force_exceeded"
"""The failure reason of a trial whose plug's true insertion force rose above the task's
``contact_force_limit_n`` (even if it reached the depth)."""


def insertion_force_violations(insertion_force_n: np.ndarray, limit_n: float) -> int:
    """How many times ``insertion_force_n`` (a series, N) rose above ``limit_n``: the number
    of runs of successive samples over it."""
    over = np.asarray(insertion_force_n) > limit_n
    return int(np.count_nonzero(over[1:] & ~over[:-1]) + (1 if over.size and over[0] else 0))


def final_insertion(depth_m: np.ndarray, required_m: float) -> int | None:
    """The index of the truth row from which the plug stays at ``required_m`` or deeper to
    the end (the start of the last run of ``depth_m`` >= it), or None when the last row is
    not at that depth. A plug that reached the depth, was pulled out and went in again is
    inserted from its last arrival, not its first."""
    at = np.asarray(depth_m) >= required_m
    if not at.size or not at[-1]:
        return None
    out = np.flatnonzero(~at)
    return int(out[-1] + 1) if out.size else 0


DONE_NOT_AT_DEPTH = "done with the plug not at the depth"
"""The failure reason of a trial whose machine finished with the plug out of the depth it
had reached before (pulled out again)."""


def _result(task, controller, seed, ran: RunOutcome, truth) -> TrialResult:
    config = task.config
    depth = truth["depth_m"]
    t = truth["t_s"]
    required = config.machine.insert.depth_m
    final = final_insertion(depth, required)
    started = ran.loop.stats.first_tick_s  # after the devices' start-up (activation)
    time_to_insert = float(t[final] - started) if final is not None else None
    done = ran.machine.phase is Phase.DONE
    contact, insertion = truth["contact_force_n"], truth["insertion_force_n"]
    violations = insertion_force_violations(insertion, config.contact_force_limit_n)
    success = done and final is not None and violations == 0
    failure = None
    if not success:
        failed = [tr for tr in ran.transitions if tr.target is Phase.FAILED]
        if violations:
            failure = INSERTION_FORCE_EXCEEDED
        elif failed:
            failure = failed[-1].reason
        elif done and bool(np.any(depth >= required)):
            failure = DONE_NOT_AT_DEPTH
        elif done:
            failure = "done without reaching the depth"
        else:
            failure = f"loop ended: {ran.loop.reason}"
    wrist = truth["wrist_wrench_t"][:, :3]
    entry_tilt, entry_inplane = entry_torques(truth, required)
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
        max_wrist_force_n=max_force,
        force_limit_n=config.force_limit_n,
        wall_time_s=ran.wall_s,
        max_contact_force_n=float(contact.max()) if len(contact) else 0.0,
        p99_contact_force_n=float(np.percentile(contact, 99)) if len(contact) else 0.0,
        max_insertion_force_n=float(insertion.max()) if len(insertion) else 0.0,
        p99_insertion_force_n=float(np.percentile(insertion, 99)) if len(insertion) else 0.0,
        contact_force_limit_n=config.contact_force_limit_n,
        insertion_force_violations=violations,
        entry_tilt_torque_rms_nm=entry_tilt,
        entry_inplane_torque_rms_nm=entry_inplane,
        **_grasp_fields(task, seed, ran),
    )


def _grasp_fields(task: Task, seed: int, ran: RunOutcome) -> dict[str, float]:
    """The plug's pose in the hand: the machine's estimates (FEEL's, where its machine has
    one: the align machine's width-plane tilt and tip, the press spiral's thickness-plane
    tilt and tip) and the scene's truth for ``seed`` (TrialResult's pose fields)."""
    # imported here: the scene's draws belong to the simulator, which a real run never loads
    from drivers.sim.scenes.insertion.coupling import imprint
    from drivers.sim.scenes.insertion.draws import draw_scene
    from evaluation.trials.grasp_truth import grasp_truth, receptacle_tilts_rad

    length = task.config.plug.length_m
    draw = draw_scene(task.config.hole, task.scene, seed)
    truth = grasp_truth(draw.grasp, length)
    # the receptacle's axis about T y and about T x (rad)
    about_y, about_x = receptacle_tilts_rad(draw.board_tilt_rad)
    estimate = getattr(ran.machine, "grasp", None)
    tilt = estimate.tilt_rad if estimate is not None else math.nan
    thickness = getattr(ran.machine, "tilt_x_estimate_rad", None)
    tip_y = getattr(ran.machine, "tip_y_estimate_m", None)
    # the press spiral's (its imprint and FEEL), else the align machine's FEEL's
    tip_x = getattr(ran.machine, "tip_x_estimate_m", None)
    face = getattr(ran.machine, "face_offset_m", None)
    if tip_x is None and estimate is not None:
        tip_x = estimate.tip_t[0]
    return {
        "grasp_tilt_est_rad": tilt,
        "grasp_tilt_true_rad": truth.tilt_width_rad,
        "grasp_tilt_thickness_true_rad": truth.tilt_thickness_rad,
        "thickness_tilt_to_receptacle_true_rad": truth.tilt_thickness_rad - about_x,
        "width_tilt_to_receptacle_true_rad": truth.tilt_width_rad - about_y,
        "grasp_tilt_thickness_est_rad": math.nan if thickness is None else thickness,
        "tip_x_est_m": math.nan if tip_x is None else float(tip_x),
        "tip_x_true_m": float(truth.tip_t_m[0]),
        "tip_y_est_m": math.nan if tip_y is None else tip_y,
        "tip_y_true_m": float(truth.tip_t_m[1]),
        "imprint_offset_est_m": math.nan if face is None else face,
        "imprint_true_m": imprint(draw.grasp)[0][0],
    }
