"""``python -m evaluation fit_axial_map``: the product's axial-force map (the press spiral by
touch, ``dipole``), fitted on recorded trials (evaluation/trials/axial_map.py).

    fit_axial_map.py --fit RECORD [RECORD ...] --check RECORD [RECORD ...]
                     [--against W1,...,W9]

Each RECORD is a trial's record folder (``run_trials.py --records``: OUT/records/*/).
Fits on the ``--fit`` records and prints the weights as the task file's
``touch_spiral.axial_weights`` line, then the RMS error (N) on the ``--check`` records
(trials the fit did not see), beside that of the ``--against`` weights (default:
``TouchSpiralConfig``'s, shear_y over a finger's share of 0.5). Writes nothing.
Bad arguments, a folder that is not a trial record: one line and exit code 2.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from controller.cli.support import ToolError, run_tool
from controller.insertion.force_reading import AXIAL_TERMS
from controller.insertion.machine_config import GripperSettings
from controller.insertion.spiral import TouchSpiralConfig
from core.subcommands import job_prog
from evaluation.trials.axial_map import fit_weights, joined, record_samples, rms_error_n


def _weights(text: str) -> tuple[float, ...]:
    try:
        values = tuple(float(v) for v in text.split(","))
    except ValueError:
        values = ()
    if len(values) != len(AXIAL_TERMS) or not all(np.isfinite(values)):
        raise argparse.ArgumentTypeError(
            f"expected {len(AXIAL_TERMS)} numbers separated by commas, got {text!r}"
        )
    return values


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=job_prog("fit_axial_map"), description=__doc__.splitlines()[0]
    )
    parser.add_argument("--fit", nargs="+", type=Path, required=True, help="records to fit on")
    parser.add_argument("--check", nargs="+", type=Path, required=True, help="records to check on")
    parser.add_argument(
        "--against", type=_weights, help=f"weights to compare ({', '.join(AXIAL_TERMS)})"
    )
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    return run_tool("fit_axial_map", lambda: _run(args))


def _run(args: argparse.Namespace) -> int:
    overlap = {p.resolve() for p in args.fit} & {p.resolve() for p in args.check}
    if overlap:
        raise ToolError(f"{sorted(overlap)[0]}: in both --fit and --check (expected disjoint)")
    fitted = fit_weights(joined([record_samples(p) for p in args.fit]))
    check = joined([record_samples(p) for p in args.check])
    default = TouchSpiralConfig(GripperSettings()).axial_weights
    against = np.asarray(args.against if args.against is not None else default)
    print("axial_weights: [" + ", ".join(f"{w:.6g}" for w in fitted) + "]")
    print(f"  # {', '.join(AXIAL_TERMS)}")
    print(
        f"RMS error on {len(args.check)} checked trials ({len(check.force_n)} frames): "
        f"fitted {rms_error_n(fitted, check):.3f} N, against {rms_error_n(against, check):.3f} N"
    )
    return 0
