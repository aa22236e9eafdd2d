"""Write a simulated calibration dataset (the jig scene; format: controller/offline/dataset.py).

    python -m evaluation make_dataset OUT [--sensor gelsight_mini|digit] [--object plate|
        square_peg|round_peg] [--axes x y z] [--amplitudes-nmm 20 40 60]
        [--frames-per-axis 12500] [--scene calibration_jig] [--seed 0]

The paper's runs held about 12,500 frames per axis. Calibrate with tactile calibrate OUT.
OUT must not exist; it is checked (and every argument) before any work. The dataset is
built in a hidden folder beside OUT and renamed to OUT only when complete: an error or an
interruption leaves no OUT. Expected failures print one line ``make_dataset: error: ...``
and exit with code 2; SIGINT and SIGTERM exit with 130 and 143 (controller/cli/support.py).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

from controller.cli.outputs import check_output_folder
from controller.cli.support import (
    SEED,
    ToolError,
    distinct,
    integer,
    number,
    resolved_config_path,
    run_tool,
)
from core.sensor_profile import sensor_profile
from core.subcommands import job_prog
from drivers.sim.gel.profile import SHAPES
from evaluation.common.rendering import make_renderer
from evaluation.common.sim_setup import gel_model, jig_config
from evaluation.offline.jig_dataset import MAX_FRAMES_PER_AXIS, paper_experiments, write_jig_dataset


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=job_prog("make_dataset"), description=__doc__.splitlines()[0]
    )
    parser.add_argument("out", type=Path, help="dataset folder to write (must not exist)")
    parser.add_argument(
        "--sensor", default="gelsight_mini", help="sensor profile (its gel: SENSOR_gel.yaml)"
    )
    parser.add_argument("--object", default="plate", choices=sorted(SHAPES))
    parser.add_argument("--axes", nargs="+", default=["x", "y"], choices=["x", "y", "z"])
    parser.add_argument(
        "--amplitudes-nmm",
        nargs="+",
        type=number(0.1, 1000.0, "N*mm"),
        default=[20.0, 40.0, 60.0],
        help="peak torques the hand applies, N*mm",
    )
    parser.add_argument("--frames-per-axis", type=integer(1, MAX_FRAMES_PER_AXIS), default=12500)
    parser.add_argument("--scene", default="calibration_jig", help="configs/scenes name or path")
    parser.add_argument("--seed", type=SEED, default=0)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    distinct(parser, "--axes", args.axes)
    return run_tool("make_dataset", lambda: make_dataset(args))


def make_dataset(args: argparse.Namespace) -> int:
    """Check every argument and OUT, then simulate and write the dataset."""
    scene = resolved_config_path(args.scene, "scenes")
    check_output_folder(args.out, [scene], option="OUT", must_not_exist=True)
    sensor_profile(args.sensor)
    try:
        config = jig_config(args.scene)
        model = gel_model(args.sensor, args.object)
        renderer = make_renderer(args.sensor, seed=args.seed)
        experiments = paper_experiments(
            args.axes, [a * 1e-3 for a in args.amplitudes_nmm], args.frames_per_axis, config
        )
        start = time.perf_counter()
        timing = write_jig_dataset(
            args.out, args.sensor, model, renderer, experiments, config, seed=args.seed
        )
    except ValueError as exc:  # a ConfigError, or a setting the simulator refuses
        raise ToolError(str(exc)) from None
    elapsed = time.perf_counter() - start
    sim_rate = timing["frames"] / (timing["physics_s"] + timing["render_s"])
    print(
        f"make_dataset: wrote {timing['frames']:.0f} frames to {args.out} in {elapsed:.1f} s "
        f"(physics + render {sim_rate:.0f} frames/s)"
    )
    return 0
