"""Score the estimator's slip flags on the simulated gel (evaluation/slip_eval.py).

    python scripts/eval_slip.py [--method NAME] [--grips 10,7,14] [--seed 11]
        [--noise-grey 1.0] [--objects plate,square_peg] [--quick] [--out SLIP.md]

``make evaluate`` runs the same evaluation and puts its tables in docs/EVALUATION.md; this
script is for trying other estimator configurations, grips or objects on their own.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from drivers.sim.gel.profile import SHAPES
from evaluation.machine import cpu_model
from evaluation.slip_eval import GRIPS_N, OBJECTS, evaluate
from evaluation.slip_report import slip_tables


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="eval_slip", description=__doc__.splitlines()[0])
    parser.add_argument(
        "--method", default=None, help="estimator configuration (default: the Mini's own)"
    )
    parser.add_argument(
        "--grips",
        default=",".join(f"{g:g}" for g in GRIPS_N),
        help="grip forces, N (first: tuning)",
    )
    parser.add_argument("--seed", type=int, default=11)
    parser.add_argument("--noise-grey", type=float, default=1.0, help="camera noise sigma")
    parser.add_argument("--out", type=Path, help="write the markdown report here")
    parser.add_argument("--objects", default=",".join(OBJECTS), help="objects to grasp")
    parser.add_argument("--quick", action="store_true", help="two sequences per object")
    args = parser.parse_args(argv)
    try:
        grips = tuple(float(g) for g in args.grips.split(","))
    except ValueError:
        parser.error(f"--grips {args.grips!r}: expected comma-separated forces in N, e.g. 10,7")
    if any(g <= 0 for g in grips):
        parser.error(f"--grips {args.grips!r}: every grip force must be > 0 N")
    objects = tuple(args.objects.split(","))
    unknown = sorted(set(objects) - set(SHAPES))
    if unknown:
        parser.error(f"unknown object {unknown[0]!r}; expected some of {', '.join(SHAPES)}")
    began = time.perf_counter()
    report = evaluate(args.method, grips, args.seed, args.noise_grey, objects, args.quick)
    seconds = time.perf_counter() - began
    text = "\n".join(
        [
            "# Slip detection on the simulated gel",
            "",
            f"Estimator `{report['method']}`, seed {report['seed']}, camera noise "
            f"{report['noise_grey']:g} grey levels; {report['overall']['frames']} frames in "
            f"{seconds:.0f} s on {cpu_model()}. Thresholds were chosen on the "
            f"{report['tuned_on_grip_n']:g} N grip.",
            "",
            *slip_tables(report),
        ]
    )
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(text + "\n")
    sys.stdout.write(text + "\n")
    return 0
