"""Render real-texture recordings and check estimators on them.

    python -m evaluation check_real_recordings [--estimators default,dis_half,paper]
        [--captures all] [--work out/real_recordings] [--seed 0] [--table FILE]

For each capture of drivers/sim/render/real_gels/, the press-tilt-release program is rendered
on it and written to WORK as ``<capture>.mkv`` with its truth ``<capture>.csv``
(evaluation/real_recordings/recording_video.py); each estimator's estimate goes beside them as
``<capture>.<estimator>.csv``, made by ``tactile estimate``'s code, and is checked
(evaluation/real_recordings/recording_checks.py). The markdown table (estimator x capture)
is printed, and written to ``--table`` when given. Exit code 0 when every check passed, 1
when one failed, 2 for bad input (one line ``check_real_recordings: error: ...``).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from controller.cli.outputs import atomic_text, check_output_file
from controller.cli.support import ToolError, run_tool
from controller.tactile import estimator_for_sensor
from core.sensor_profile import sensor_profile
from core.subcommands import job_prog
from drivers.sim.render.real_texture import real_gel_names
from evaluation.real_recordings.recording_checks import (
    QUIET_MAX,
    SIGN_FLOOR,
    SIGN_MIN,
    check_recording,
    table,
)
from evaluation.real_recordings.recording_video import render_recording

PROG = "check_real_recordings"
DEFAULT_ESTIMATORS = "default,dis_half,paper"


def _names(text: str, option: str, known: tuple[str, ...] | None = None) -> list[str]:
    names = [name.strip() for name in text.split(",") if name.strip()]
    if not names:
        raise ToolError(f"{option} '{text}': expected a comma-separated list of names")
    unknown = [name for name in names if known is not None and name not in known]
    if unknown:
        raise ToolError(f"{option}: unknown {', '.join(unknown)}; expected {', '.join(known)}")
    return names


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog=job_prog(PROG), description=__doc__.splitlines()[0])
    parser.add_argument(
        "--estimators",
        default=DEFAULT_ESTIMATORS,
        help="comma-separated names in configs/estimators/ or YAML paths",
    )
    parser.add_argument(
        "--captures", default="all", help=f"all, or some of {', '.join(real_gel_names())}"
    )
    parser.add_argument("--work", type=Path, default=Path("out/real_recordings"))
    parser.add_argument("--seed", type=int, default=0, help="seed of the camera noise")
    parser.add_argument("--table", type=Path, default=None, help="also write the table here")
    args = parser.parse_args(argv)

    def body() -> int:
        estimators = _names(args.estimators, "--estimators")
        captures = (
            list(real_gel_names())
            if args.captures == "all"
            else _names(args.captures, "--captures", real_gel_names())
        )
        for name in estimators:  # fail before rendering anything
            estimator_for_sensor(sensor_profile("gelsight_mini"), name)
        if args.table is not None:
            check_output_file(args.table, (), option="--table")
        if args.work.exists() and not args.work.is_dir():
            raise ToolError(f"--work '{args.work}' is not a folder")
        checks = []
        for capture in captures:
            render_recording(capture, args.work, seed=args.seed)
            checks += [check_recording(capture, args.work, name) for name in estimators]
        lines = [
            f"Checks (pass: finite on every frame, quiet ratio <= {QUIET_MAX:g}, sign agreement "
            f">= {SIGN_MIN:.0%} of frames above {SIGN_FLOOR:.0%} of the peak in every tilt "
            "segment, correlation > 0):",
            "",
            *table(checks),
        ]
        print("\n".join(lines))
        if args.table is not None:
            with atomic_text(args.table) as handle:
                handle.write("\n".join(lines) + "\n")
        return 0 if all(c.passed for c in checks) else 1

    return run_tool(PROG, body)
