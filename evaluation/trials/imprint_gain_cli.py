"""``python -m evaluation fit_imprint_gain``: the gain of the grasp's imprint (the press
spiral's ``touch_spiral.imprint_gain``, controller/insertion/imprint.py), fitted on finished
trials.

    python -m evaluation fit_imprint_gain --fit DIR [DIR ...] --check DIR [DIR ...]

Each DIR is a batch folder of a tactile controller whose imprint was read (``tactile trials
--out DIR``, with the task's gain or ``--set touch_spiral.imprint_gain=G``, any G > 0): its
``trials.csv`` holds, per trial, the plug's offset the machine took from the imprint
(``imprint_offset_est_m``) and where the plug's axis truly crosses the gel's centre row
(``imprint_true_m``); its ``batch.json`` names the task and the overrides, whose gain turns
the offset back into the contact centre read. The gain is the least-squares slope through
the origin of that centre on the truth over the ``--fit`` trials, printed as the task
file's line; then the offset's error with it (mm) on the ``--check`` trials: RMS, median
and largest. Writes nothing. A DIR that is not a batch's folder, in both lists, or without
a trial that read an imprint: one line and exit code 2.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from controller.cli.support import ToolError, run_tool
from controller.run.task import load_task
from core.config import ConfigError
from core.subcommands import job_prog
from evaluation.trials.batch import read_batch


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=job_prog("fit_imprint_gain"), description=__doc__.splitlines()[0]
    )
    parser.add_argument("--fit", nargs="+", type=Path, required=True, help="batches to fit on")
    parser.add_argument("--check", nargs="+", type=Path, required=True, help="batches to check")
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    return run_tool("fit_imprint_gain", lambda: _run(args))


def imprint_pairs(folders: list[Path]) -> tuple[np.ndarray, np.ndarray]:
    """(contact centres read, true offsets), m along T x, of the trials of ``folders`` that
    read an imprint."""
    read, true = [], []
    for folder in folders:
        plan, results = read_batch(folder)
        try:
            config = load_task(plan["task"], list(plan.get("overrides", []))).config
        except ConfigError as exc:
            raise ToolError(f"'{folder}': batch.json's task does not load ({exc})") from None
        gain = config.touch_spiral.imprint_gain
        rows = [r for r in results if np.isfinite(r.imprint_offset_est_m)]
        if not rows or gain == 0.0:
            raise ToolError(
                f"'{folder}': no trial read an imprint (expected a tactile controller's batch "
                "with touch_spiral.imprint_gain > 0)"
            )
        read += [r.imprint_offset_est_m * gain for r in rows]
        true += [r.imprint_true_m for r in rows]
    return np.asarray(read), np.asarray(true)


def fit_gain(read: np.ndarray, true: np.ndarray) -> float:
    """The slope through the origin of ``read`` on ``true`` (least squares)."""
    return float(read @ true / (true @ true))


def _run(args: argparse.Namespace) -> int:
    overlap = {p.resolve() for p in args.fit} & {p.resolve() for p in args.check}
    if overlap:
        raise ToolError(f"{sorted(overlap)[0]}: in both --fit and --check (expected disjoint)")
    gain = fit_gain(*imprint_pairs(args.fit))
    read, true = imprint_pairs(args.check)
    error_mm = np.abs(read / gain - true) * 1e3
    print(f"imprint_gain: {gain:.4f}")
    print(
        f"offset error on {len(read)} checked trials: RMS "
        f"{float(np.sqrt(np.mean(error_mm**2))):.3f} mm, median {float(np.median(error_mm)):.3f}"
        f" mm, largest {float(error_mm.max()):.3f} mm"
    )
    return 0
