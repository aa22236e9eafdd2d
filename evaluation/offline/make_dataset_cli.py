"""Write a simulated calibration dataset (the jig scene; format: evaluation/offline/dataset.py).

    python scripts/make_dataset.py OUT [--sensor gelsight_mini|digit] [--object plate|
        square_peg|round_peg] [--axes x y z] [--amplitudes-nmm 20 40 60]
        [--frames-per-axis 12500] [--scene calibration_jig] [--seed 0]

The paper's runs held about 12,500 frames per axis. Calibrate with scripts/calibrate.py OUT.
Expected failures print one line ``make_dataset: error: ...`` and exit with code 2.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from drivers.config import ConfigError
from drivers.sim.gel.profile import SHAPES
from evaluation.jig_dataset import paper_experiments, write_jig_dataset
from evaluation.rendering import make_renderer
from evaluation.sim_setup import gel_model, jig_config


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="make_dataset", description=__doc__.splitlines()[0])
    parser.add_argument("out", type=Path, help="dataset folder to write")
    parser.add_argument("--sensor", default="gelsight_mini", help="gel profile: SENSOR_gel.yaml")
    parser.add_argument("--object", default="plate", choices=sorted(SHAPES))
    parser.add_argument("--axes", nargs="+", default=["x", "y"], choices=["x", "y", "z"])
    parser.add_argument(
        "--amplitudes-nmm",
        nargs="+",
        type=float,
        default=[20.0, 40.0, 60.0],
        help="peak torques the hand applies, N*mm",
    )
    parser.add_argument("--frames-per-axis", type=int, default=12500)
    parser.add_argument("--scene", default="calibration_jig", help="configs/scenes name or path")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    try:
        config = jig_config(args.scene)
        model = gel_model(args.sensor, args.object)
        experiments = paper_experiments(
            args.axes, [a * 1e-3 for a in args.amplitudes_nmm], args.frames_per_axis, config
        )
        start = time.perf_counter()
        timing = write_jig_dataset(
            args.out,
            args.sensor,
            model,
            make_renderer(args.sensor, seed=args.seed),
            experiments,
            config,
            seed=args.seed,
        )
    except (ConfigError, ValueError) as exc:
        print(f"make_dataset: error: {exc}", file=sys.stderr)
        return 2
    elapsed = time.perf_counter() - start
    sim_rate = timing["frames"] / (timing["physics_s"] + timing["render_s"])
    print(
        f"make_dataset: wrote {timing['frames']:.0f} frames to {args.out} in {elapsed:.1f} s "
        f"(physics + render {sim_rate:.0f} frames/s)"
    )
    return 0
