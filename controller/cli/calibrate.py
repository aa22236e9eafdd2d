"""Fit the torque constants of an estimator on a calibration dataset, recorded or simulated.

    tactile calibrate DATASET [--method NAME] [--out calibration.yaml]

Runs the estimator over the dataset's frames (zeroed on its reference interval), fits each
axis that has segments (c_x, c_y and c_z: our dipole / NHHD torque, and the FingerVision
baseline's, side by side), prints a table of slope, RMSE (N*mm) and R^2, and writes the
calibration file (``Calibration.to_yaml``: the fits, and the sensor profile and estimator
configuration they were fitted for) that ``tactile estimate --calibration`` reads.

``--out`` is checked before any work (not an input, writable) and written atomically. An
incomplete or inconsistent dataset, or an axis with segments that cannot be fitted, is an
error. Expected failures print one line ``calibrate: error: ...`` and exit with code 2;
SIGINT and SIGTERM exit with 130 and 143 (controller/cli/support.py).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from controller.cli.outputs import check_output_file, write_text
from controller.cli.support import ToolError, resolved_config_path, run_tool
from controller.offline.dataset import Dataset
from controller.offline.dataset_fit import calibration_from_fits, estimate_dataset, fit_dataset
from controller.tactile import estimator_for_sensor
from controller.tactile.calibration import AxisFit
from core.config import ConfigError
from core.sensor_profile import sensor_profile
from core.subcommands import job_prog


def fit_table(fits: dict[tuple[str, str], AxisFit]) -> str:
    """A markdown table: one row per axis, ours and the baseline side by side."""
    lines = [
        "| axis | ours: slope | ours: RMSE (N*mm) | ours: R^2 "
        "| baseline: slope | baseline: RMSE (N*mm) | baseline: R^2 | samples |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for axis in sorted({axis for axis, _ in fits}):
        ours, base = fits[(axis, "ours")], fits[(axis, "baseline")]
        lines.append(
            f"| tau_{axis} | {ours.slope:.4g} | {ours.rmse * 1e3:.3f} | {ours.r2:.4f} "
            f"| {base.slope:.4g} | {base.rmse * 1e3:.3f} | {base.r2:.4f} | {ours.samples} |"
        )
    return "\n".join(lines)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=job_prog("calibrate"), description="Fit c_x, c_y (and c_z) on a calibration dataset."
    )
    parser.add_argument("dataset", type=Path, help="dataset folder (controller/offline/dataset.py)")
    parser.add_argument(
        "--method",
        default=None,
        help="estimator configuration name or YAML path (default: the sensor profile's)",
    )
    parser.add_argument("--out", type=Path, default=None, help="calibration YAML to write")
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    return run_tool("calibrate", lambda: calibrate(args.dataset, args.method, args.out))


def calibrate(folder: Path, method: str | None, out: Path | None) -> int:
    """Check the output, fit the dataset in ``folder``, print the table, write ``out``."""
    if out is not None:
        check_output_file(out, [folder, resolved_config_path(method, "estimators")])
    dataset = Dataset(folder)
    profile = sensor_profile(dataset.meta.sensor)
    estimator = estimator_for_sensor(profile, method)
    method = estimator.config_name
    try:
        series = estimate_dataset(dataset, estimator)
        fits = fit_dataset(dataset, series)
    except ConfigError:
        raise
    except ValueError as exc:
        raise ToolError(str(exc)) from None
    if not fits:
        raise ToolError(f"{folder}: the dataset has no segments to fit")
    print(
        f"calibrate: {len(dataset)} frames of {folder} ({dataset.meta.sensor}, "
        f"{method}); median estimator time {np.median(series.latency_ms):.2f} ms"
    )
    print(fit_table(fits))
    if out is not None:
        write_text(out, calibration_from_fits(fits, profile.name, estimator).to_yaml())
        print(f"calibrate: wrote {out}")
    return 0
