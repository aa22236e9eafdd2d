"""The dipole's origin under pushing, scored on the true field (evaluation/realgel/origins.py).

    python -m evaluation realgel_origins [--estimators default,paper] [--dipole-grids config]
        [--amplitudes 0.4] [--frames 160] [--seed 0]

``--dipole-grids``: "config" (each configuration's own), or comma-separated "COLSxROWS" /
"field" (the field's grid) applied to every configuration that can pool to it.
"""

from __future__ import annotations

import argparse
import sys

from controller.tactile.settings import dipole_grid_mismatch, estimator_config, field_grid
from core.config import ConfigError
from core.subcommands import job_prog
from evaluation.common.machine_info import git_revision
from evaluation.realgel.check import sequence_specs
from evaluation.realgel.check_cli import _numbers
from evaluation.realgel.origins import origin_scores, table, with_dipole_grid
from evaluation.realgel.textures import SIZE_HW


def _grids(parser: argparse.ArgumentParser, text: str) -> list[str]:
    grids = text.split(",")
    for grid in grids:
        parts = grid.split("x")
        if grid in ("config", "field"):
            continue
        if len(parts) != 2 or not all(p.isdigit() and 3 <= int(p) <= 64 for p in parts):
            parser.error(f"--dipole-grids {grid!r}: expected config, field or COLSxROWS (3-64)")
    return grids


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog=job_prog("realgel_origins"), description=__doc__.splitlines()[0]
    )
    parser.add_argument("--estimators", default="default,paper")
    parser.add_argument("--dipole-grids", default="config")
    parser.add_argument("--amplitudes", default="0.4")
    parser.add_argument("--frames", type=int, default=160)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)
    amplitudes = _numbers(parser, "--amplitudes", args.amplitudes)
    if args.frames < 8:
        parser.error(f"--frames {args.frames}: expected at least 8")
    grids = _grids(parser, args.dipole_grids)
    configs = []
    for name in args.estimators.split(","):
        try:
            config = estimator_config(name)
        except ConfigError as error:
            parser.error(f"--estimators: {error}")
        for grid in grids:
            label = name if grid == "config" else f"{name}, dipole grid {grid}"
            variant = config if grid == "config" else with_dipole_grid(config, grid)
            if dipole_grid_mismatch(variant, *field_grid(variant, *SIZE_HW)) is None:
                configs.append((label, variant))  # else: that grid cannot pool this field
    specs = [
        spec
        for spec in sequence_specs(["gelsight_markers_a"], amplitudes, args.frames, args.seed)
        if spec.push > 0
    ]
    results = [
        (label, spec, origin_scores(spec, config)) for label, config in configs for spec in specs
    ]
    command = "python -m evaluation realgel_origins " + " ".join(
        argv if argv is not None else sys.argv[1:]
    )
    lines = [
        f"`{command.strip()}` — revision {git_revision()}: held-out R² of the tilt on the true "
        "field, pushing sequences, per origin of the dipole moment.",
        "",
        *table(results),
    ]
    sys.stdout.write("\n".join(lines) + "\n")
    return 0
