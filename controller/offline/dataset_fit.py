"""Run an estimator over a calibration dataset and fit its torque constants (c_x, c_y, c_z).

Per axis, the fit uses the frames captured during that axis's segments and the live gel's
wrench from the F/T readings (``Dataset.gel_truth``), interpolated to the frame times
(``calibration.fit_axis``). Each axis is fitted for the dipole / NHHD estimate and for the
FingerVision baseline, side by side.
"""

from __future__ import annotations

import time
from collections.abc import Iterable
from dataclasses import dataclass
from typing import cast

import numpy as np

from controller.offline.dataset import Dataset
from controller.tactile import TactileEstimator
from controller.tactile.calibration import AxisFit, Calibration, estimator_sha256, fit_axis
from controller.tactile.wrench import VALUE_FIELDS

# axis -> (our estimate, the baseline's, the torque column of a (fx..tau_z) row)
TORQUE_AXES = {
    "x": ("tau_x", "fv_tau_x", 3),
    "y": ("tau_y", "fv_tau_y", 4),
    "z": ("tau_z", "fv_tau_z", 5),
}
METHODS = ("ours", "baseline")


@dataclass(frozen=True)
class EstimateSeries:
    """Raw estimates of every frame: ``t_s`` (n,), ``values[name]`` (n,) for each of
    VALUE_FIELDS, the slip flags ``slip_suspected`` and ``slip_gross`` (n,) bool, and the
    estimator's time per frame ``latency_ms``."""

    t_s: np.ndarray
    values: dict[str, np.ndarray]
    slip_suspected: np.ndarray
    slip_gross: np.ndarray
    latency_ms: np.ndarray


def estimate_frames(
    frames: Iterable[tuple[int, float, np.ndarray]],
    reference: list[np.ndarray],
    estimator: TactileEstimator,
    open_gel: list[np.ndarray] | None = None,
) -> EstimateSeries:
    """Estimates for ``frames`` ((index, t_s, image) tuples) against the mean of
    ``reference`` (which replaces the estimator's), with ``open_gel`` the frames of the open
    gel before the grasp (``TactileEstimator.set_open_reference``; None: none)."""
    estimator.set_open_reference(open_gel)
    estimator.set_reference(reference)
    t_s, rows, slip, gross, latency = [], [], [], [], []
    for _, t, image in frames:
        start = time.perf_counter()
        estimate = estimator.push(image, t)
        latency.append((time.perf_counter() - start) * 1e3)
        t_s.append(t)
        rows.append([getattr(estimate, name) for name in VALUE_FIELDS])
        slip.append(estimate.slip_suspected)
        gross.append(estimate.slip_gross)
    table = np.array(rows, float).reshape(-1, len(VALUE_FIELDS))
    return EstimateSeries(
        np.array(t_s),
        {name: table[:, i] for i, name in enumerate(VALUE_FIELDS)},
        np.array(slip, bool),
        np.array(gross, bool),
        np.array(latency),
    )


def reference_frames(dataset: Dataset, interval: tuple[float, float]) -> list[np.ndarray]:
    """The frames captured in ``interval`` (e.g. ``dataset.meta.reference``)."""
    chosen = dataset.in_interval(interval)
    frames = [image for index, _, image in dataset.frames() if chosen[index]]
    if not frames:
        raise ValueError(f"{dataset.folder}: no frame lies in the interval {interval}")
    return frames


def estimate_dataset(
    dataset: Dataset, estimator: TactileEstimator, zero_on: str = "reference"
) -> EstimateSeries:
    """Estimates for every frame, zeroed on the ``reference`` interval (after the grasp) or
    on the ``open`` one (before it: no zeroing after the grasp). Zeroed on the grasp, the
    estimator also sees the ``open`` interval's frames, if the dataset has them, as the open
    gel (the ``grasp_centroid`` dipole origin's contact centre)."""
    interval = dataset.meta.reference if zero_on == "reference" else dataset.meta.open
    if interval is None:
        raise ValueError(f"{dataset.folder}: the dataset has no '{zero_on}' interval")
    open_gel = None
    if zero_on == "reference" and dataset.meta.open is not None:
        open_gel = reference_frames(dataset, dataset.meta.open)
    return estimate_frames(
        dataset.frames(), reference_frames(dataset, interval), estimator, open_gel
    )


def segment_mask(dataset: Dataset, t_s: np.ndarray, axis: str) -> np.ndarray:
    """Samples at ``t_s`` that fall in a segment about ``axis``."""
    mask = np.zeros(t_s.shape, bool)
    for segment in dataset.meta.segments:
        if segment.axis == axis:
            mask |= (t_s >= segment.t_start_s) & (t_s < segment.t_end_s)
    return mask


def fit_dataset(
    dataset: Dataset, series: EstimateSeries, axes: Iterable[str] | None = None
) -> dict[tuple[str, str], AxisFit]:
    """Fits keyed by (axis, method) for each of ``axes`` (default: every axis the dataset
    has segments for). An axis that cannot be fitted (no or too few frames of ``series``
    in its segments) is a ValueError naming it, never silently left out."""
    truth_t, truth = dataset.gel_truth()
    fits = {}
    wanted = {s.axis for s in dataset.meta.segments} if axes is None else set(axes)
    for axis, (ours, baseline, column) in TORQUE_AXES.items():
        if axis not in wanted:
            continue
        mask = segment_mask(dataset, series.t_s, axis)
        for method, name in zip(METHODS, (ours, baseline), strict=True):
            try:
                fits[(axis, method)] = fit_axis(
                    series.t_s[mask], series.values[name][mask], truth_t, truth[:, column]
                )
            except ValueError as exc:
                raise ValueError(
                    f"{dataset.folder}: cannot fit tau_{axis} ({method}): {exc}"
                ) from None
    return fits


def calibration_from_fits(
    fits: dict[tuple[str, str], AxisFit], sensor: str, estimator: TactileEstimator
) -> Calibration:
    """A calibration file's content: every fitted axis, ours and the baseline's, and what
    it was fitted for (the sensor profile's name, the estimator's configuration name and the
    fingerprint of its values)."""
    axes = {}
    for (axis, method), fit in fits.items():
        ours, baseline, _ = TORQUE_AXES[axis]
        axes[ours if method == "ours" else baseline] = fit
    name = cast(str, estimator.config_name)  # the configuration's name or path it was built from
    return Calibration(sensor, name, axes, estimator_sha256(estimator.config))
