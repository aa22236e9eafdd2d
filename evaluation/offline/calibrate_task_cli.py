"""Fit a task's calibration in its simulated scene (part of the task's set-up).

    python -m evaluation calibrate_task --task usb_c [--seed 0] [--set KEY=VALUE ...]
        --out configs/calibrations/usb_c.yaml

Applies known wrenches to the grasped plug in the task's scene, records the estimator's raw
estimates and the scene's true gel wrench, fits a line per axis (evaluation/offline/
scene_calibration.py), prints a table of slope, RMSE, R^2 and the calibrated noise at rest,
and writes the calibration file (``Calibration.to_yaml``, versioned by the estimator's
fingerprint and the grasp's scene) that the task file names with ``calibration:``. The task
is loaded without its calibration, so a stale one is refitted rather than refused.

``--out`` is checked before any work (not an input, writable) and written atomically. Bad
arguments or keys: one line ``calibrate_task: error: ...`` and exit code 2.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from controller.cli.outputs import check_output_file, write_text
from controller.cli.support import add_override_argument, integer, run_tool
from controller.run.insertion_trial import MAX_SEED
from controller.run.task import load_task
from controller.tactile.calibration import Calibration
from core.subcommands import job_prog
from evaluation.offline.scene_calibration import fit_scene_calibration, record_in_scene


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=job_prog("calibrate_task"), description=__doc__.splitlines()[0]
    )
    parser.add_argument("--task", required=True, help="usb_c, usb_a or a task YAML path")
    parser.add_argument(
        "--seed",
        type=integer(0, MAX_SEED),
        default=0,
        help="the scene's seed (its draws, the plug's pose in the grasp among them, and the "
        "pixel noise)",
    )
    add_override_argument(parser, "override a task key by dotted path (repeatable)")
    parser.add_argument("--out", type=Path, required=True, help="calibration YAML to write")
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    return run_tool("calibrate_task", lambda: _calibrate(args))


def _calibrate(args: argparse.Namespace) -> int:
    task = load_task(args.task, args.overrides, with_calibration=False)
    check_output_file(args.out, [task.path])
    calibration = fit_scene_calibration(record_in_scene(task, args.seed), task)
    print(f"calibrate_task: {task.config.task} ({task.path}), seed {args.seed}")
    print(fit_table(calibration))
    write_text(args.out, calibration.to_yaml())
    print(f"calibrate_task: wrote {args.out}")
    return 0


def fit_table(calibration: Calibration) -> str:
    """A markdown table: one row per axis (units: N*m for torques, N for forces)."""
    lines = [
        "| axis | slope (truth per raw) | RMSE | R^2 | noise at rest | samples |",
        "|---|---:|---:|---:|---:|---:|",
    ]
    for axis, fit in calibration.axes.items():
        rest = "-" if fit.rest_std is None else f"{fit.rest_std:.3g}"
        lines.append(
            f"| {axis} | {fit.slope:.4g} | {fit.rmse:.3g} | {fit.r2:.4f} | {rest} | {fit.samples} |"
        )
    return "\n".join(lines)
