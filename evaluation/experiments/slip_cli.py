"""Score the estimator's slip flags on the simulated gel (evaluation/experiments/slip_eval.py).

    python -m evaluation eval_slip [--method NAME] [--grips 10,7,14] [--seed 11]
        [--noise-grey 1.0] [--objects plate,square_peg] [--quick] [--out SLIP.md]

``make evaluate`` runs the same evaluation and puts its tables in docs/EVALUATION.md; this
script is for trying other estimator configurations, grips or objects on their own.
Arguments and ``--out`` are checked before any work; the report is written atomically.
Bad input exits with code 2 and one line; SIGINT and SIGTERM with 130 and 143.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from controller.cli.outputs import check_output_file, write_text
from controller.cli.support import (
    SEED,
    distinct,
    number,
    number_list,
    one_line,
    resolved_config_path,
    run_tool,
)
from controller.tactile.settings import sensor_estimator
from core.config import ConfigError
from core.sensor_profile import sensor_profile
from core.subcommands import job_prog
from drivers.sim.gel.profile import SHAPES
from evaluation.common.machine_info import cpu_model
from evaluation.experiments.slip_eval import GRIPS_N, OBJECTS, SENSOR, evaluate
from evaluation.experiments.slip_tables import slip_tables


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog=job_prog("eval_slip"), description=__doc__.splitlines()[0]
    )
    parser.add_argument(
        "--method", default=None, help="estimator configuration (default: the Mini's own)"
    )
    parser.add_argument(
        "--grips",
        type=str,
        default=",".join(f"{g:g}" for g in GRIPS_N),
        help="grip forces, N (first: tuning)",
    )
    parser.add_argument("--seed", type=SEED, default=11)
    parser.add_argument(
        "--noise-grey",
        type=number(0.0, 50.0, "grey levels"),
        default=1.0,
        help="camera noise sigma",
    )
    parser.add_argument("--out", type=Path, help="write the markdown report here")
    parser.add_argument("--objects", default=",".join(OBJECTS), help="objects to grasp")
    parser.add_argument("--quick", action="store_true", help="two sequences per object")
    args = parser.parse_args(argv)
    try:
        grips = number_list(0.1, 200.0, "N")(args.grips)
    except argparse.ArgumentTypeError:
        parser.error(
            f"--grips {args.grips!r}: expected comma-separated forces in N, e.g. 10,7; "
            "every grip force must be > 0 N (at most 200 N)"
        )
    objects = args.objects.split(",")
    unknown = sorted(set(objects) - set(SHAPES))
    if unknown:
        parser.error(f"unknown object {unknown[0]!r}; expected some of {', '.join(SHAPES)}")
    distinct(parser, "--objects", objects)
    try:
        method, _ = sensor_estimator(sensor_profile(SENSOR), args.method)
    except ConfigError as exc:
        parser.error(f"--method: {one_line(exc)}")
    return run_tool("eval_slip", lambda: _run(args, method, grips, tuple(objects)))


def _run(args: argparse.Namespace, method: str, grips: tuple[float, ...], objects) -> int:
    if args.out:
        check_output_file(args.out, [resolved_config_path(method, "estimators")])
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
        write_text(args.out, text + "\n")
    sys.stdout.write(text + "\n")
    return 0
