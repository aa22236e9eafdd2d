"""Linear calibration of raw tactile estimates against ground truth (a force/torque sensor).

The two series come at different rates and with their own timestamps: the ground truth is
linearly interpolated to the tactile timestamps (tactile samples outside the ground truth's
time span are dropped), then each axis gets a least-squares fit

    truth ~= slope * raw + intercept        (intercept fixed at 0 unless ``with_offset``)

so ``slope`` is the paper's c_x / c_y (units: N*m per raw unit). A calibration file holds the
fits of several axes (``tau_x``, ``tau_y``, ..., and the baseline's ``fv_tau_x``, ...) and
is applied to WrenchEstimates; axes absent from the file stay raw.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from controller.tactile.wrench import VALUE_FIELDS, WrenchEstimate
from drivers.config import ConfigError, load_yaml

FORMAT = "tactile-insertion/calibration/v1"
AXES = VALUE_FIELDS
_MIN_SAMPLES = 3


@dataclass(frozen=True)
class AxisFit:
    """One axis: ``truth ~= slope * raw + intercept``, with the fit's RMSE (truth units), R^2
    and the number of samples used."""

    slope: float
    intercept: float
    rmse: float
    r2: float
    samples: int

    def apply(self, raw: float) -> float:
        return self.slope * raw + self.intercept


def _series(name: str, values: np.ndarray) -> np.ndarray:
    array = np.asarray(values, dtype=float)
    if array.ndim != 1:
        raise ValueError(f"{name} must be one-dimensional, got shape {array.shape}")
    if not np.isfinite(array).all():
        raise ValueError(f"{name} contains NaN or inf")
    return array


def fit_axis(
    estimate_t_s: np.ndarray,
    estimate: np.ndarray,
    truth_t_s: np.ndarray,
    truth: np.ndarray,
    with_offset: bool = False,
) -> AxisFit:
    """Fit ``truth ~= slope * estimate (+ intercept)`` after interpolating the truth, sampled at
    ``truth_t_s``, to ``estimate_t_s`` (both in seconds on the same clock)."""
    est_t, est = _series("estimate_t_s", estimate_t_s), _series("estimate", estimate)
    gt_t, gt = _series("truth_t_s", truth_t_s), _series("truth", truth)
    if est_t.shape != est.shape or gt_t.shape != gt.shape:
        raise ValueError("each series needs as many timestamps as values")
    order = np.argsort(gt_t, kind="stable")
    gt_t, gt = gt_t[order], gt[order]
    inside = (est_t >= gt_t[0]) & (est_t <= gt_t[-1]) if gt_t.size else np.zeros(est_t.shape, bool)
    if inside.sum() < _MIN_SAMPLES:
        raise ValueError(
            f"only {int(inside.sum())} estimate samples fall inside the ground truth's time span; "
            f"expected at least {_MIN_SAMPLES} (are both series on the same clock?)"
        )
    x = est[inside]
    y = np.interp(est_t[inside], gt_t, gt)
    if with_offset:
        design = np.stack([x, np.ones_like(x)], axis=1)
        (slope, intercept), *_ = np.linalg.lstsq(design, y, rcond=None)
    else:
        denominator = float(x @ x)
        slope, intercept = (float(x @ y) / denominator if denominator > 0 else 0.0), 0.0
    residual = y - (slope * x + intercept)
    total = float(((y - y.mean()) ** 2).sum())
    r2 = 1.0 - float(residual @ residual) / total if total > 0 else 0.0
    rmse = float(np.sqrt(np.mean(residual**2)))
    return AxisFit(float(slope), float(intercept), rmse, r2, int(x.size))


@dataclass(frozen=True)
class Calibration:
    """Per-axis fits for one sensor and estimator configuration."""

    sensor: str
    estimator: str
    axes: dict[str, AxisFit]

    def __post_init__(self) -> None:
        unknown = sorted(set(self.axes) - set(AXES))
        if unknown:
            raise ValueError(f"unknown calibration axis '{unknown[0]}'; expected one of {AXES}")

    def apply(self, estimate: WrenchEstimate) -> WrenchEstimate:
        """The estimate with each calibrated axis scaled (and offset); others unchanged."""
        values = {axis: fit.apply(getattr(estimate, axis)) for axis, fit in self.axes.items()}
        return dataclasses.replace(estimate, calibrated=True, **values)

    def save(self, path: Path | str) -> None:
        document = {
            "format": FORMAT,
            "sensor": self.sensor,
            "estimator": self.estimator,
            "axes": {axis: dataclasses.asdict(fit) for axis, fit in self.axes.items()},
        }
        Path(path).write_text(yaml.safe_dump(document, sort_keys=False))

    @classmethod
    def load(cls, path: Path | str) -> Calibration:
        """Read a calibration file; errors name the file and the offending key."""
        data = load_yaml(path)
        if data.get("format") != FORMAT:
            raise ConfigError(
                f"{path}: key 'format': expected '{FORMAT}', got {data.get('format')!r}"
            )
        for key in ("sensor", "estimator", "axes"):
            if key not in data:
                raise ConfigError(f"{path}: missing key '{key}'")
        axes = {}
        fields = [f.name for f in dataclasses.fields(AxisFit)]
        for axis, fit in (data["axes"] or {}).items():
            if axis not in AXES:
                raise ConfigError(f"{path}: unknown key 'axes.{axis}'; expected one of {AXES}")
            if not isinstance(fit, dict) or sorted(fit) != sorted(fields):
                raise ConfigError(f"{path}: key 'axes.{axis}': expected the keys {fields}")
            if not all(isinstance(fit[k], int | float) and np.isfinite(fit[k]) for k in fields):
                raise ConfigError(f"{path}: key 'axes.{axis}': expected finite numbers")
            axes[axis] = AxisFit(**fit)
        return cls(str(data["sensor"]), str(data["estimator"]), axes)
