"""``tactile trial``: one insertion trial, simulated (default) or on the robot.

    tactile trial --task usb_c|usb_a|PATH.yaml [--backend sim|real] [--seed N] --out DIR
                  [--controller dipole|fingervision|zero_torque|torque_only|align|blind|oracle]
                  [--realtime] [--set KEY=VALUE ...] [--episode-images jpeg|png]

It prints the phase timeline and the outcome, and writes into DIR the trial's episode
(``episode.mcap``: every stream, docs/EPISODES.md; its tactile frames as JPEG, or losslessly
as PNG with ``--episode-images png``), its record (controller/run/record.py: ticks.jsonl,
transitions.jsonl, truth.npz, trial.json) and ``summary.png`` (estimated torques with
phase bands, the wrist's true force, the tip's true
path). ``--set`` overrides any key of the task file by its dotted path, checked as the file
is. ``--realtime`` paces the simulation to the wall clock; the default runs as fast as
possible. Times printed are seconds from the run's start. Exit codes as every tool's
(controller/cli/support.py); a trial that fails still exits 0 (the outcome is the
result), but one that ended in a fault (a watchdog trip, an exception in a tick) exits 1
after its safe stop with one line naming it (controller/cli/run_outcome.py); a run
stopped by SIGINT/SIGTERM exits 130/143 after its safe stop, with the record kept.

On the robot (``--backend real``) the trial is the product's (controller/run/insertion_trial.py). In
simulation it is scored against the simulator's truth by the trial tools of evaluation/
(``SIMULATION``), imported by name only then: a run on the robot never loads them, nor the
simulator (the product never imports evaluation/ or drivers.sim: tests/test_layers.py).
"""

from __future__ import annotations

import argparse
import importlib
from pathlib import Path

from controller.cli.outputs import check_output_folder
from controller.cli.run_outcome import fault_exit, signal_exit
from controller.cli.support import ToolError, add_override_argument, integer, run_tool
from controller.episode.session import EPISODE_FILE, EpisodeOptions
from controller.run import CONTROLLERS
from controller.run.insertion_trial import MAX_SEED, TrialOutcome, run
from controller.run.task import load_task
from core.subcommands import job_prog

SIMULATION = "evaluation.trials.trial"
"""The module whose ``run`` (with ``run``'s signature) runs a trial in simulation, scored
against the simulator's truth, and whose ``write_trial_chart(folder, result)`` draws its
``summary.png``: imported only for ``--backend sim``."""

SIM_ONLY_CONTROLLERS = ("oracle",)
"""The controllers that read the simulator's truth (evaluation/trials/oracle.py): sim only."""


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=job_prog("run_trial"), description=__doc__.splitlines()[0]
    )
    parser.add_argument("--task", required=True, help="usb_c, usb_a or a task YAML path")
    parser.add_argument("--backend", choices=("sim", "real"), default="sim")
    parser.add_argument("--seed", type=integer(0, MAX_SEED), default=0)
    parser.add_argument(
        "--controller", choices=[*CONTROLLERS, *SIM_ONLY_CONTROLLERS], default="dipole"
    )
    parser.add_argument("--realtime", action="store_true", help="pace to the wall clock")
    add_override_argument(
        parser, "override a task key by dotted path, e.g. scene.friction=0.5 (repeatable)"
    )
    parser.add_argument(
        "--episode-images",
        choices=("jpeg", "png"),
        default="jpeg",
        help="the episode's tactile frames: jpeg (small) or png (lossless, exact re-estimation)",
    )
    parser.add_argument("--out", type=Path, required=True, help="output folder (new or empty)")
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.backend == "real" and args.controller in SIM_ONLY_CONTROLLERS:
        parser.error("argument --controller: 'oracle' reads the simulator's truth: sim only")
    return run_tool("run_trial", lambda: _run(args))


def _run(args: argparse.Namespace) -> int:
    task = load_task(args.task, args.overrides, args.backend)
    check_output_folder(args.out, [task.path], option="--out")
    if args.out.exists() and any(args.out.iterdir()):
        raise ToolError(f"--out '{args.out}': the folder is not empty")
    simulation = importlib.import_module(SIMULATION) if args.backend == "sim" else None
    outcome = (simulation.run if simulation is not None else run)(
        task,
        args.controller,
        args.seed,
        backend=args.backend,
        realtime=args.realtime,
        paced=True,
        out_dir=args.out,
        episode=EpisodeOptions(image_format=args.episode_images),
    )
    print(timeline(outcome))
    if simulation is not None and outcome.truth is not None:
        simulation.write_trial_chart(args.out, outcome.result)
    print(f"run_trial: wrote {args.out}")
    episode = args.out / EPISODE_FILE
    print(f"run_trial: episode {episode}; summarise it with:")
    print(f"  .venv/bin/tactile replay summary {episode}")
    stopped = signal_exit(
        "run_trial", outcome.loop, f"the record is complete up to then: {args.out}"
    )
    if stopped is not None:
        return stopped
    return fault_exit("run_trial", outcome.loop)


def timeline(outcome: TrialOutcome) -> str:
    """The phase timeline and the outcome, for the terminal."""
    result = outcome.result
    lines = [f"{'t (s)':>8}  phase change (reason)"]
    for tr in outcome.transitions:
        lines.append(f"{tr.t_s:8.2f}  {tr.source.value} -> {tr.target.value} ({tr.reason})")
    verdict = "INSERTED" if result.success else f"FAILED ({result.failure_reason})"
    lines.append(
        f"outcome: {verdict} in {result.duration_s:.2f} s"
        + (
            f", depth reached {result.time_to_insert_s:.2f} s after the controller started "
            f"(at {outcome.loop.stats.first_tick_s:.2f} s)"
            if result.success
            else ""
        )
        + (
            f"; true plug insertion force max {result.max_insertion_force_n:.2f} N, p99 "
            f"{result.p99_insertion_force_n:.2f} N (limit {result.contact_force_limit_n:g} N, "
            f"{result.insertion_force_violations} violations), summed contact force max "
            f"{result.max_contact_force_n:.2f} N; max true wrist force "
            f"{result.max_wrist_force_n:.2f} N (limit {result.force_limit_n:g} N)"
            if result.max_wrist_force_n == result.max_wrist_force_n
            else ""
        )
        + f"; {result.duration_s / max(result.wall_time_s, 1e-9):.1f}x real time"
    )
    loop = outcome.loop.stats
    lines.append(
        f"loop: {loop.ticks} ticks, {loop.overruns} overruns, period p50/p99/max "
        f"{loop.period_p50_s * 1e3:.2f}/{loop.period_p99_s * 1e3:.2f}/"
        f"{loop.period_max_s * 1e3:.2f} ms"
    )
    return "\n".join(lines)
