"""The paper's calibration experiment in simulation: a dataset per sensor and object, the
torque constants fitted on it for the dipole / NHHD method and the FingerVision baseline, and
the charts (estimate against ground truth coloured by experiment; time series)."""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import matplotlib.pyplot as plt
import numpy as np

from controller.offline.dataset import Dataset
from controller.offline.dataset_fit import (
    TORQUE_AXES,
    EstimateSeries,
    calibration_from_fits,
    estimate_dataset,
    fit_dataset,
    segment_mask,
)
from controller.tactile import Calibration, estimator_for_sensor
from controller.tactile.calibration import AxisFit
from evaluation.common.rendering import make_renderer
from evaluation.common.sim_setup import gel_model, jig_config
from evaluation.offline.jig_dataset import paper_experiments, write_jig_dataset

NOMINAL_AMPLITUDES_NM = (0.02, 0.04, 0.06)  # applied by the hand; each gel carries half


@dataclass(frozen=True)
class CalibrationCase:
    """One calibration run: ``appearance`` is a renderer appearance name
    (drivers/sim/render/appearance.py), None for the sensor's nominal realistic one."""

    sensor: str
    shape: str
    axes: tuple[str, ...] = ("x", "y", "z")
    frames_per_axis: int = 600
    seed: int = 0
    appearance: str | None = None

    @property
    def name(self) -> str:
        """ "SENSOR-SHAPE", with "-APPEARANCE" appended (':' as '_') when not nominal."""
        suffix = "" if self.appearance is None else "-" + self.appearance.replace(":", "_")
        return f"{self.sensor}-{self.shape}{suffix}"


@dataclass
class CaseResult:
    case: CalibrationCase
    folder: Path
    fits: dict[tuple[str, str], AxisFit]
    calibration: Calibration
    series: EstimateSeries
    generation: dict[str, float]
    lifted_off_share: float
    slipping_share: float


def run_case(case: CalibrationCase, root: Path, estimator: str | None = None) -> CaseResult:
    """Write the case's dataset under ``root``, run the estimator (None: the sensor's own)
    on it and fit."""
    config = jig_config()
    folder = root / case.name
    experiments = paper_experiments(case.axes, NOMINAL_AMPLITUDES_NM, case.frames_per_axis, config)
    start = time.perf_counter()
    timing = write_jig_dataset(
        folder,
        case.sensor,
        gel_model(case.sensor, case.shape),
        make_renderer(case.sensor, seed=case.seed, appearance=case.appearance),
        experiments,
        config,
        seed=case.seed,
        replace=True,
    )
    timing["total_s"] = time.perf_counter() - start
    dataset = Dataset(folder)
    tactile = estimator_for_sensor(case.sensor, estimator)
    series = estimate_dataset(dataset, tactile)
    fits = fit_dataset(dataset, series)
    truth = dataset.truth or {}
    return CaseResult(
        case,
        folder,
        fits,
        calibration_from_fits(fits, case.sensor, tactile),
        series,
        timing,
        float(np.mean(truth.get("lifted_off", [0.0]))),
        float(np.mean(np.asarray(truth.get("slip_fraction", [0.0])) > 0)),
    )


def scatter_chart(result: CaseResult, path: Path) -> None:
    """Calibrated estimate against the F/T ground truth per axis, ours and the baseline,
    coloured by experiment (the paper's main figure)."""
    dataset = Dataset(result.folder)
    truth_t, truth = dataset.gel_truth()
    axes = sorted({axis for axis, _ in result.fits})
    fig, grid = plt.subplots(2, len(axes), figsize=(4 * len(axes), 7.5), squeeze=False)
    for col, axis in enumerate(axes):
        ours_name, base_name, column = TORQUE_AXES[axis]
        gt = np.interp(result.series.t_s, truth_t, truth[:, column]) * 1e3
        for row, (method, name) in enumerate((("ours", ours_name), ("baseline", base_name))):
            ax = grid[row][col]
            fit = result.fits[(axis, method)]
            estimate = fit.apply(result.series.values[name]) * 1e3
            for segment in dataset.meta.segments:
                if segment.axis != axis:
                    continue
                inside = (result.series.t_s >= segment.t_start_s) & (
                    result.series.t_s < segment.t_end_s
                )
                ax.scatter(
                    gt[inside],
                    estimate[inside],
                    s=4,
                    alpha=0.5,
                    label=f"{segment.amplitude_nm * 1e3:.0f} N*mm applied",
                )
            lim = np.abs(gt[segment_mask(dataset, result.series.t_s, axis)]).max() * 1.2
            ax.plot([-lim, lim], [-lim, lim], "k--", lw=0.8)
            label = "dipole" if axis != "z" else "NHHD"
            title = label if method == "ours" else "FingerVision baseline"
            ax.set_title(
                f"tau_{axis}, {title}: R^2 {fit.r2:.3f}, RMSE {fit.rmse * 1e3:.2f} N*mm", fontsize=9
            )
            ax.set_xlabel("F/T ground truth (N*mm)")
            ax.set_ylabel("calibrated estimate (N*mm)")
            ax.set_xlim(-lim, lim)
            ax.set_ylim(-lim, lim)
            ax.legend(fontsize=7, markerscale=3)
    look = result.case.appearance or "realistic"
    fig.suptitle(
        f"Calibration, {result.case.sensor}, {result.case.shape}, {look} images (simulated jig)"
    )
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


def timeseries_chart(result: CaseResult, path: Path, seconds: float = 40.0) -> None:
    """The first ``seconds`` of each axis's experiments: ground truth, our calibrated
    estimate and the baseline's."""
    dataset = Dataset(result.folder)
    truth_t, truth = dataset.gel_truth()
    axes = sorted({axis for axis, _ in result.fits})
    fig, grid = plt.subplots(len(axes), 1, figsize=(10, 2.6 * len(axes)), squeeze=False)
    for row, axis in enumerate(axes):
        ours_name, base_name, column = TORQUE_AXES[axis]
        start = min(s.t_start_s for s in dataset.meta.segments if s.axis == axis)
        t = result.series.t_s
        window = (t >= start) & (t < start + seconds)
        ft_window = (truth_t >= start) & (truth_t < start + seconds)
        ax = grid[row][0]
        ax.plot(
            truth_t[ft_window] - start,
            truth[ft_window, column] * 1e3,
            "k-",
            lw=1,
            label="F/T ground truth",
        )
        series = (
            ("ours", ours_name, "dipole" if axis != "z" else "NHHD", 1.0),
            ("baseline", base_name, "FingerVision baseline", 0.7),
        )
        for method, name, label, alpha in series:
            values = result.fits[(axis, method)].apply(result.series.values[name]) * 1e3
            ax.plot(t[window] - start, values[window], ".-", ms=3, lw=0.8, alpha=alpha, label=label)
        ax.set_ylabel(f"tau_{axis} (N*mm)")
        ax.legend(fontsize=8, loc="upper right")
    grid[-1][0].set_xlabel("time in the experiment (s)")
    fig.suptitle(f"Ground truth against calibrated estimates, {result.case.name}")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)
