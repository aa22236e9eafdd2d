"""Linear calibration of raw tactile estimates against ground truth (a force/torque sensor).

The two series come at different rates and with their own timestamps: the ground truth is
linearly interpolated to the tactile timestamps (tactile samples outside the ground truth's
time span are dropped), then each axis gets a least-squares fit

    truth ~= slope * raw + intercept        (intercept fixed at 0 unless ``with_offset``)

so ``slope`` is the paper's c_x / c_y (units: N*m per raw unit). A calibration file holds the
fits of several axes (``tau_x``, ``tau_y``, ..., and the baseline's ``fv_tau_x``, ...) and
is applied to WrenchEstimates; axes absent from the file stay raw.

A calibration file records what it was fitted for: the sensor profile's name and the
estimator configuration's name and fingerprint (``estimator_sha256``); a calibration fitted
in a task's simulated scene (``python -m evaluation calibrate_task``) also records the task and the
fingerprint of the scene it was fitted in (``scene``, ``scene_sha256``; None for the offline
calibration on a dataset), and each axis's noise at rest (``AxisFit.rest_std``, truth
units). ``mismatch`` says why a calibration does not fit another sensor or configuration;
the tools refuse to apply it then (``tactile estimate --force`` overrides). Files load
through the configuration loader (``core.config``) into these frozen dataclasses.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import re
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from controller.tactile.settings import EstimatorConfig
from controller.tactile.wrench import VALUE_FIELDS, WrenchEstimate
from core.config import Config, ConfigError, build, config_dataclass, load_yaml, number

FORMAT = "tactile-insertion/calibration/v2"
FORMAT_V1 = "tactile-insertion/calibration/v1"
AXES = VALUE_FIELDS
_MIN_SAMPLES = 3


@config_dataclass
class AxisFit(Config):
    """One axis: ``truth ~= slope * raw + intercept``, with the fit's RMSE (truth units), R^2
    and the number of samples used; ``rest_std``: the standard deviation of the calibrated
    estimate with no load change (truth units: N*m or N), where it was measured (None
    otherwise)."""

    slope: float
    intercept: float
    rmse: float = number(0.0, math.inf)
    r2: float
    samples: int = number(1, 2**62)
    rest_std: float | None = number(0.0, math.inf, default=None)

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


def estimator_sha256(config: EstimatorConfig) -> str:
    """Fingerprint of an estimator configuration (a dataclass): SHA-256 of its values as
    sorted JSON. Two configurations with equal values have equal fingerprints, whatever
    their file names."""
    text = json.dumps(dataclasses.asdict(config), sort_keys=True, default=str)
    return hashlib.sha256(text.encode()).hexdigest()


@config_dataclass
class Calibration(Config):
    """Per-axis fits for one sensor profile (``sensor``: its name) and estimator
    configuration (``estimator``: its name or path, ``estimator_sha256``: the fingerprint of
    its values; None for a file written before fingerprints were recorded)."""

    sensor: str
    estimator: str
    axes: Mapping[str, AxisFit]
    estimator_sha256: str | None = None
    scene: str | None = None
    scene_sha256: str | None = None

    def __post_init__(self) -> None:
        unknown = sorted(set(self.axes) - set(AXES))
        if unknown:
            raise ValueError(
                f"unknown key 'axes.{unknown[0]}'; expected calibration axes among: "
                + ", ".join(AXES)
            )
        for key in ("estimator_sha256", "scene_sha256"):
            digest = getattr(self, key)
            if digest is not None and not re.fullmatch(r"[0-9a-f]{64}", digest):
                raise ValueError(f"key '{key}': expected 64 hexadecimal digits, got {digest!r}")

    def mismatch(self, sensor: str, config: EstimatorConfig) -> str | None:
        """Why this calibration does not fit the sensor profile named ``sensor`` with the
        estimator configuration ``config``; None when it does."""
        if sensor != self.sensor:
            return f"it was fitted for sensor '{self.sensor}', not '{sensor}'"
        if self.estimator_sha256 is None:
            return (
                "it does not record which estimator configuration it was fitted for "
                f"(format {FORMAT_V1}); re-run tactile calibrate"
            )
        if estimator_sha256(config) != self.estimator_sha256:
            return (
                f"it was fitted for the estimator configuration '{self.estimator}', and the "
                "one in use has other values"
            )
        return None

    def apply(self, estimate: WrenchEstimate) -> WrenchEstimate:
        """The estimate with each calibrated axis scaled (and offset); others unchanged."""
        values: dict[str, Any] = {
            axis: fit.apply(getattr(estimate, axis)) for axis, fit in self.axes.items()
        }
        return dataclasses.replace(estimate, calibrated=True, **values)

    def to_yaml(self) -> str:
        """The calibration file's text (format v2)."""
        document = {
            "format": FORMAT,
            "sensor": self.sensor,
            "estimator": self.estimator,
            "estimator_sha256": self.estimator_sha256,
            **({"scene": self.scene} if self.scene is not None else {}),
            **({"scene_sha256": self.scene_sha256} if self.scene_sha256 is not None else {}),
            "axes": {axis: _axis_document(fit) for axis, fit in self.axes.items()},
        }
        return yaml.safe_dump(document, sort_keys=False)

    def rest_std(self, axis: str) -> float:
        """The calibrated noise at rest of ``axis`` (truth units); ValueError when the file
        does not record it (only a calibration fitted in a scene does)."""
        fit = self.axes.get(axis)
        if fit is None or fit.rest_std is None:
            raise ValueError(
                f"the calibration records no noise at rest for '{axis}' "
                "(re-run python -m evaluation calibrate_task)"
            )
        return fit.rest_std

    @classmethod
    def load(cls, path: Path | str) -> Calibration:
        """Read a calibration file (format v2, or v1 without the estimator fingerprint)
        through the configuration loader; errors name the file and the offending key."""
        return cls.from_document(load_yaml(path), str(path))

    @classmethod
    def from_document(cls, document: Mapping[str, Any], path: str) -> Calibration:
        """The calibration of a file's parsed ``document`` (its mapping), read from ``path``
        (a file's name, or where the text came from, for the errors)."""
        data = dict(document)
        found = data.pop("format", None)
        if found not in (FORMAT, FORMAT_V1):
            raise ConfigError(f"{path}: key 'format': expected '{FORMAT}', got {found!r}")
        if found == FORMAT_V1:
            for key in ("estimator_sha256", "scene", "scene_sha256"):
                if key in data:
                    raise ConfigError(f"{path}: unknown key '{key}' in format {found}")
            data["estimator_sha256"] = None
        data.setdefault("scene", None)  # optional: only a calibration fitted in a scene
        data.setdefault("scene_sha256", None)
        axes = data.get("axes")
        if isinstance(axes, Mapping):
            for axis in axes:
                if axis not in AXES:
                    raise ConfigError(
                        f"{path}: unknown key 'axes.{axis}'; expected calibration axes among: "
                        + ", ".join(AXES)
                    )
            data["axes"] = {
                axis: {"rest_std": None, **fit} if isinstance(fit, Mapping) else fit
                for axis, fit in axes.items()
            }
        return build(cls, data, source=str(path))


def _axis_document(fit: AxisFit) -> dict[str, Any]:
    """One axis as written: ``rest_std`` only where it was measured (older readers)."""
    document = dataclasses.asdict(fit)
    if fit.rest_std is None:
        del document["rest_std"]
    return document
